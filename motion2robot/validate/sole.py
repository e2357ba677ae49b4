"""Points on the soles' edges, their names, and the swing clearance a robot's feet need.

A sole is the rectangle of its four corner sites (front-left, front-right, back-right,
back-left in the foot's frame, :meth:`~motion2robot.robot.config.FootConfig.corners`). The
points of the sole that can touch a flat floor first are on its edges: the part of a flat sole
lower than a height is a convex region bounded by edges, and the speed of a rigid sole's points
is a convex function of the point, so the fastest touching point is a corner or an edge point.
:func:`edge_motion` follows ``EDGE_SEGMENTS`` points on every edge (corners included); they move
rigidly with the foot, so they are exact affine combinations of the corner positions.
Units: metres, world frame z up.
"""

from __future__ import annotations

import numpy as np

from motion2robot.robot.robot import Robot
from motion2robot.validate.options import SWING_CLEARANCE_RATIO, CheckOptions

#: Points per sole edge (the first is the edge's starting corner).
EDGE_SEGMENTS = 8

SIDES = ("left", "right")


def _weights(k: int = EDGE_SEGMENTS) -> np.ndarray:
    """(4 k, 4) weights of the corners for the points along edges 0-1, 1-2, 2-3, 3-0."""
    w = np.zeros((4 * k, 4))
    t = np.arange(k) / k
    for e in range(4):
        w[e * k:(e + 1) * k, e] = 1.0 - t
        w[e * k:(e + 1) * k, (e + 1) % 4] = t
    return w


WEIGHTS = _weights()


def edge_motion(corners: np.ndarray, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """Heights (T, 2, P) m of the edge points of (T, 2, 4, 3) sole corners, and their horizontal
    speeds (T - 1, 2, P) m/s between consecutive frames (P = 4 * EDGE_SEGMENTS)."""
    w = WEIGHTS.T                                                       # (4, P)
    d = np.diff(corners[..., :2], axis=0)                               # (T-1, 2, 4, 2)
    dx, dy = d[..., 0] @ w, d[..., 1] @ w
    return corners[..., 2] @ w, np.sqrt(dx * dx + dy * dy) * fps


def point_name(side: str, p: int, k: int = EDGE_SEGMENTS) -> str:
    """Name of edge point ``p`` of the ``side`` ("left"/"right") sole, e.g. "outer toe corner",
    "heel edge". Inner is towards the other foot."""
    edge, at = divmod(int(p), k)
    inner_right = side == "left"  # the left foot's right side faces the other foot
    lr = {"left": "inner" if not inner_right else "outer", "right": "inner" if inner_right else "outer"}
    if at == 0:
        return [f"{lr['left']} toe corner", f"{lr['right']} toe corner", f"{lr['right']} heel corner",
                f"{lr['left']} heel corner"][edge]
    return ["toe edge", f"{lr['right']} edge", "heel edge", f"{lr['left']} edge"][edge]


def swing_clearance(robot: Robot, options: CheckOptions) -> float:
    """m a swing foot keeps above the floor: ``options.swing_clearance`` or, by default,
    ``SWING_CLEARANCE_RATIO`` times the robot's standing root height above its soles."""
    if options.swing_clearance is not None:
        return float(options.swing_clearance)
    return SWING_CLEARANCE_RATIO * float(robot.nominal_qpos[2])


def yaw_rate(corners: np.ndarray, fps: float) -> np.ndarray:
    """(T - 1, 2) rad/s of each sole's heading between consecutive frames, from (T, 2, 4, 3)
    corners (the heading is the horizontal direction from the heel edge to the toe edge)."""
    fwd = corners[:, :, 0, :2] + corners[:, :, 1, :2] - corners[:, :, 2, :2] - corners[:, :, 3, :2]
    ang = np.unwrap(np.arctan2(fwd[..., 1], fwd[..., 0]), axis=0)
    return np.abs(np.diff(ang, axis=0)) * fps

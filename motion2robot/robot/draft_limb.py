"""A limb's joints grouped where their axes meet (shoulder, elbow, wrist), for drafting configs.

Pure geometry on the world-frame hinge anchors and axes at one pose (metres, z up): walking the
chain from the trunk outwards, a hinge joins the current group when all the group's axis lines and
its own pass within :data:`MEET_TOL` of one point (their least-squares meeting point), else it
starts a new group. A shoulder's pitch, roll and yaw meet in one point; the elbow hinge lies a
whole upper arm away and starts a group, which a forearm twist (its axis along the forearm, so
through the elbow axis) joins; the wrist's hinges start the next one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2robot.robot.body_geometry import axes_center

#: m; axis lines farther than this from their group's meeting point start a new group.
MEET_TOL = 0.03
#: cos of the angle under which a hinge axis counts as running along the limb (a twist).
TWIST_COS = 0.9


@dataclass(frozen=True)
class JointGroup:
    """Consecutive hinges (indices into the chain's joint list) and where their axes meet (world, m)."""

    joints: tuple[int, ...]
    centre: np.ndarray


def _meet(points: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, float]:
    c = axes_center(points, dirs, points.mean(axis=0))
    d = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    r = (c - points) - ((c - points) * d).sum(axis=1, keepdims=True) * d
    return c, float(np.linalg.norm(r, axis=1).max())


def group_joints(points: np.ndarray, dirs: np.ndarray, tol: float = MEET_TOL) -> list[JointGroup]:
    """Groups of consecutive hinges whose axes meet (module docstring). ``points`` (k, 3) anchors
    and ``dirs`` (k, 3) axes, in chain order from the trunk."""
    groups: list[list[int]] = []
    for i in range(len(points)):
        if groups:
            cand = groups[-1] + [i]
            _, res = _meet(points[cand], dirs[cand])
            if res <= tol:
                groups[-1] = cand
                continue
        groups.append([i])
    return [JointGroup(tuple(g), _meet(points[g], dirs[g])[0]) for g in groups]


def pick_shoulder_elbow_wrist(groups: list[JointGroup]) -> tuple[int, int, int | None]:
    """Indices of the shoulder, elbow and wrist groups: with three or more groups the elbow is the
    one between the two longest consecutive segments (upper arm + forearm); with two, shoulder and
    elbow, no wrist group (None)."""
    if len(groups) < 2:
        raise ValueError("fewer than two joint groups")
    if len(groups) == 2:
        return 0, 1, None
    gaps = [float(np.linalg.norm(b.centre - a.centre)) for a, b in zip(groups, groups[1:])]
    elbow = max(range(1, len(groups) - 1), key=lambda i: gaps[i - 1] + gaps[i])
    return elbow - 1, elbow, elbow + 1


def is_twist(axis: np.ndarray, along: np.ndarray) -> bool:
    """Whether a hinge axis runs along the limb direction ``along``."""
    n = np.linalg.norm(along)
    return n > 1e-9 and abs(float(axis @ along)) / (np.linalg.norm(axis) * n) > TWIST_COS

"""Rules of the hard constraints that are not plain cost terms: the support polygon, and the exact
passes that make joint and velocity limits hold whatever the optimiser did.

- Joint limits: projection (clip) after every step; exact.
- Joint velocity limits: a backward clamping pass ``q[t] in q[t+1] +- vmax / fps`` after a forward
  one; exact (and it keeps joint limits, the clamp interval being between two in-limit values).
- Support polygon: convex hull of the sole corners in contact, shrunk by a margin, as half-planes
  ``n . c_xy <= d`` (outward unit normals) for the ``balance`` term.
"""

from __future__ import annotations

import math

import numpy as np

from motion2robot.retarget import native
from motion2robot.retarget.problem import HMAX

#: Support polygon margin as a fraction of the smaller sole half-extent.
MARGIN_FRACTION = 0.25


def clamp_limits(hinges: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(T, n) hinge angles clipped into [lower, upper] (rad)."""
    return np.clip(hinges, lower, upper)


def clamp_velocity(hinges: np.ndarray, vmax: np.ndarray, fps: float) -> np.ndarray:
    """(T, n) hinge angles with |q[t+1] - q[t]| <= vmax / fps for every t (forward, then backward pass)."""
    step = np.asarray(vmax, dtype=np.float64) / fps
    fast = native.clamp_velocity(hinges, step)
    if fast is not None:
        return fast
    q = np.array(hinges, dtype=np.float64)
    for t in range(1, len(q)):
        np.clip(q[t], q[t - 1] - step, q[t - 1] + step, out=q[t])
    for t in range(len(q) - 2, -1, -1):
        np.clip(q[t], q[t + 1] - step, q[t + 1] + step, out=q[t])
    return q


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise hull vertices of (k, 2) points (Andrew's monotone chain; a handful of
    sole corners, so plain Python)."""
    pts = sorted(set(map(tuple, np.round(np.asarray(points, dtype=float), 12).tolist())))
    if len(pts) <= 2:
        return np.array(pts, dtype=float).reshape(-1, 2)

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    upper: list = []
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def halfplanes(hull: np.ndarray, margin: float) -> np.ndarray:
    """(HMAX, 3) rows (nx, ny, d): the hull shrunk by ``margin`` is {c : n . c <= d}; unused
    rows are (0, 0, 1) (never violated)."""
    out = [(0.0, 0.0, 1.0)] * HMAX
    pts = np.asarray(hull, dtype=float).tolist()
    k = len(pts)
    for i in range(min(k, HMAX)):
        (ax, ay), (bx, by) = pts[i], pts[(i + 1) % k]
        ex, ey = bx - ax, by - ay
        norm = max(math.hypot(ex, ey), 1e-12)
        nx, ny = ey / norm, -ex / norm  # outward for a ccw hull
        out[i] = (nx, ny, nx * ax + ny * ay - margin)
    return np.array(out)


def support_planes(anchors: np.ndarray, labels: np.ndarray, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """Per frame (T, HMAX, 3) half-planes of the shrunk support polygon of the pinned sole corners
    ``anchors`` (T, 2, 4, 3) in contact, and (T,) whether the frame has support."""
    T = labels.shape[0]
    planes = np.tile([0.0, 0.0, 1.0], (T, HMAX, 1))
    support = labels.any(axis=1)
    if not support.any():
        return planes, support
    # frames of one contact phase (or pair of phases) share their polygon: one hull per run of
    # frames with the same pinned corners (feet not in contact marked with a value no corner has)
    keys = np.where(labels[:, :, None, None], anchors[..., :2], np.inf).reshape(T, -1)
    cuts = np.flatnonzero((keys[1:] != keys[:-1]).any(axis=1)) + 1
    cache: dict[bytes, np.ndarray] = {}
    for a, b in zip(np.concatenate([[0], cuts]), np.concatenate([cuts, [T]])):
        if not support[a]:
            continue
        key = keys[a].tobytes()
        if key not in cache:
            pts = keys[a].reshape(-1, 2)
            cache[key] = halfplanes(convex_hull(pts[np.isfinite(pts[:, 0])]), margin)
        planes[a:b] = cache[key]
    return planes, support


def support_margin(com_xy: np.ndarray, planes: np.ndarray) -> np.ndarray:
    """(T,) signed distance (m) of the CoM inside the shrunk polygon (>= 0 inside)."""
    return -np.max(np.einsum("thk,tk->th", planes[..., :2], com_xy) - planes[..., 2], axis=1)

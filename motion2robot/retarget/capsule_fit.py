"""A capsule around a point cloud (a mesh's vertices): the self-collision capsule of bodies whose
collision geoms are meshes (:mod:`~motion2robot.retarget.collision`).

The axis is the cloud's principal direction through its centroid; the radius is the largest
distance of a point from that line; the segment is then the shortest one along the axis whose
capsule still holds every point (a point at axial position s and distance d from the axis needs
the segment to reach s - sqrt(r^2 - d^2) .. s + sqrt(r^2 - d^2)). MuJoCo collides a mesh as the
convex hull of its vertices, which a capsule holding the vertices holds too. Bounding-box
capsules of meshes are much fatter (Unitree G1 hip-yaw link: radius 0.125 m from its box,
0.067 m here), which made the retargeter keep the legs apart further than the robot needs.
"""

from __future__ import annotations

import numpy as np


def fit_capsule(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Segment ends (3,), (3,) and radius (m) of a capsule holding every one of ``points`` (k, 3)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    centre = pts.mean(axis=0)
    rel = pts - centre
    axis = np.linalg.svd(rel, full_matrices=False)[2][0] if len(pts) > 1 else np.array([0.0, 0.0, 1.0])
    s = rel @ axis
    d = np.linalg.norm(rel - np.outer(s, axis), axis=1)
    r = float(d.max(initial=0.0))
    reach = np.sqrt(np.maximum(r * r - d * d, 0.0))
    lo, hi = float(np.min(s + reach)), float(np.max(s - reach))
    if lo > hi:  # every point within r of one axial position
        lo = hi = 0.5 * (lo + hi)
    return centre + lo * axis, centre + hi * axis, r

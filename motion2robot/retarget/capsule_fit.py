"""A capsule around a point cloud (a mesh's vertices): the self-collision capsule of bodies whose
collision geoms are meshes (:mod:`~motion2robot.retarget.collision`).

For an axis direction ``a``, the thinnest capsule along ``a`` has as radius that of the smallest
circle enclosing the points projected on the plane normal to ``a`` (:func:`enclosing_circle`),
and as axis the line through that circle's centre; the segment is then the shortest one along
the axis whose capsule still holds every point (a point at axial position s and distance d from
the axis needs the segment to reach s - sqrt(r^2 - d^2) .. s + sqrt(r^2 - d^2)). The direction is
searched from the cloud's principal axes (a pattern search on the sphere, radius as the
criterion). MuJoCo collides a mesh as the convex hull of its vertices, which a capsule holding
the vertices holds too.

Bounding-box capsules of meshes are much fatter (Unitree G1 hip-yaw link: radius 0.125 m from its
box), and so is the capsule around the principal axis through the centroid (G1 upper arm: 0.058 m,
0.044 m here; hip yaw 0.067 -> 0.061 m), which made the retargeter keep limbs further apart than
the robot needs, or drop pairs whose capsules already touched at the nominal posture.
"""

from __future__ import annotations

import math

import numpy as np

#: Angular steps (rad) of the axis pattern search, coarse to fine.
SEARCH_STEPS = (0.2, 0.1, 0.05, 0.025, 0.0125)
#: Axis directions tried besides the principal axes: the 13 of a 26-direction set, one per +-pair.
_HEMISPHERE = [np.array(v, dtype=float) / np.linalg.norm(v) for v in
               [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, -1, 0), (1, 0, 1), (1, 0, -1), (0, 1, 1), (0, 1, -1),
                (1, 1, 1), (1, 1, -1), (1, -1, 1), (1, -1, -1)]]
#: Moves at most per step size of a pattern search.
SEARCH_MOVES = 25
#: Pattern searches run, from the best of those directions.
SEARCH_STARTS = 2


def _circle_2(a: tuple, b: tuple) -> tuple[float, float, float]:
    cx, cy = (a[0] + b[0]) / 2, (a[1] + b[1]) / 2
    return cx, cy, math.hypot(a[0] - cx, a[1] - cy)


def _circle_3(a: tuple, b: tuple, c: tuple) -> tuple[float, float, float]:
    """Circumcircle of three points (the largest two-point circle if they are collinear)."""
    bx, by = b[0] - a[0], b[1] - a[1]
    cx, cy = c[0] - a[0], c[1] - a[1]
    d = 2 * (bx * cy - by * cx)
    if abs(d) < 1e-18:
        return max((_circle_2(a, b), _circle_2(a, c), _circle_2(b, c)), key=lambda x: x[2])
    ux = (cy * (bx * bx + by * by) - by * (cx * cx + cy * cy)) / d
    uy = (bx * (cx * cx + cy * cy) - cx * (bx * bx + by * by)) / d
    return a[0] + ux, a[1] + uy, math.hypot(ux, uy)


def _welzl(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Smallest circle holding ``points`` (k, 2): Welzl's algorithm, iterative form, given
    order (plain floats: a handful of candidate points)."""
    pts = [tuple(p) for p in points.tolist()]
    tol = 1e-12

    def out(p, c):
        return math.hypot(p[0] - c[0], p[1] - c[1]) > c[2] + tol

    c = (pts[0][0], pts[0][1], 0.0)
    for i in range(1, len(pts)):
        if not out(pts[i], c):
            continue
        c = (pts[i][0], pts[i][1], 0.0)
        for j in range(i):
            if not out(pts[j], c):
                continue
            c = _circle_2(pts[i], pts[j])
            for k in range(j):
                if out(pts[k], c):
                    c = _circle_3(pts[i], pts[j], pts[k])
    return np.array(c[:2]), c[2]


#: Directions whose extreme points seed :func:`enclosing_circle`.
_SEED = np.stack([np.cos(np.linspace(0, 2 * np.pi, 32, endpoint=False)),
                  np.sin(np.linspace(0, 2 * np.pi, 32, endpoint=False))], axis=1)


def enclosing_circle(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Smallest circle (centre (2,), radius) holding every one of ``points`` (k, 2), exact:
    Welzl's algorithm on a small candidate set (the extreme points in 32 directions), to which
    the farthest points outside the circle are added until none is."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    cand = np.unique(np.argmax(pts @ _SEED.T, axis=0))
    while True:
        centre, r = _welzl(pts[cand])
        dist = np.linalg.norm(pts - centre, axis=1)
        out = np.where(dist > r + 1e-12)[0]
        if not len(out):
            return centre, r
        far = out[np.argsort(dist[out])[-8:]]
        cand = np.concatenate([far, cand])  # new points first: Welzl meets them early


def _basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    u = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    return u, np.cross(axis, u)


def _radius(pts: np.ndarray, axis: np.ndarray) -> tuple[float, np.ndarray]:
    """Thinnest capsule radius along ``axis`` and a point on its axis line."""
    u, v = _basis(axis)
    c, r = enclosing_circle(np.stack([pts @ u, pts @ v], axis=1))
    return r, c[0] * u + c[1] * v


def _search(rel: np.ndarray, axis: np.ndarray, radius: float) -> tuple[float, np.ndarray]:
    """Pattern search on the sphere from ``axis`` for the thinnest capsule's direction."""
    for step in SEARCH_STEPS:
        improved, moves = True, 0
        while improved and moves < SEARCH_MOVES:
            improved, moves = False, moves + 1
            u, v = _basis(axis)
            for t in (u, -u, v, -v):
                a = axis * np.cos(step) + t * np.sin(step)
                a /= np.linalg.norm(a)
                r = _radius(rel, a)[0]
                if r < radius - 1e-9:
                    radius, axis, improved = r, a, True
                    break  # the next directions are taken about the new axis
    return radius, axis


def fit_capsule(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Segment ends (3,), (3,) and radius (m) of a thin capsule holding every one of ``points``
    (k, 3) (see the module docstring)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(pts) < 2:
        p = pts[0] if len(pts) else np.zeros(3)
        return p.copy(), p.copy(), 0.0
    centre = pts.mean(axis=0)
    rel = pts - centre
    starts = [*np.linalg.svd(rel, full_matrices=False)[2], *_HEMISPHERE]
    radii = [_radius(rel, a)[0] for a in starts]
    best_r, best_axis = np.inf, starts[0]
    for i in np.argsort(radii)[:SEARCH_STARTS]:  # local search from the best starts (local minima)
        r, axis = _search(rel, starts[i], radii[i])
        if r < best_r - 1e-9:
            best_r, best_axis = r, axis
    r, through = _radius(rel, best_axis)
    s = rel @ best_axis
    d = np.linalg.norm(rel - through - np.outer(s, best_axis), axis=1)
    reach = np.sqrt(np.maximum(r * r - d * d, 0.0))
    lo, hi = float(np.min(s + reach)), float(np.max(s - reach))
    if lo > hi:  # every point within r of one axial position
        lo = hi = 0.5 * (lo + hi)
    base = centre + through
    return base + lo * best_axis, base + hi * best_axis, r

"""A body as a convex polytope (a 14-DOP): the self-collision shape of chunky bodies (a torso, a
pelvis) that no capsule fits (:mod:`~motion2robot.retarget.collision`).

The polytope is ``{x : n_k . x <= h_k}`` in the body's frame for the 14 directions ``n_k`` of
:data:`DIRECTIONS` (the faces and corners of a cube; the 12 edge directions of a 26-DOP gave the
same clearances on OP3, G1 and H1 at the nominal posture, at twice the cost), ``h_k`` the support of the body's
collision geoms in that direction (exact per geom type; a mesh by the vertices of its convex
hull, which is what MuJoCo collides). It holds the geoms, and is much tighter than a capsule
around a box-like torso: on the Unitree G1 the upper arm's capsule is 10 mm from the torso's
polytope at the nominal posture (MuJoCo: 22 mm between the meshes), while any capsule around the
torso already swallows the upper arm there.

Clearance of a capsule (segment a-b, radius r) from the polytope: the capsule is covered by
spheres on its segment, ``n`` of them at spacing ``s <= SPHERE_SPACING`` with radius
``sqrt(r^2 + s^2/4)``; a sphere centre's clearance is ``max_k (n_k . p - h_k)`` (the signed
distance when the nearest feature is a face, a lower bound otherwise: never an overstatement),
and the capsule's the smallest over its spheres minus their radius (one constraint row per sphere).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import casadi as ca
import mujoco
import numpy as np

from motion2robot.robot.kinematics import quat_to_mat_np

#: The 14 unit directions of the polytope's faces (body frame): cube faces and corners.
DIRECTIONS = np.array([v for v in itertools.product((-1.0, 0.0, 1.0), repeat=3) if sum(map(abs, v)) in (1, 3)])
DIRECTIONS /= np.linalg.norm(DIRECTIONS, axis=1)[:, None]
#: Largest spacing (m) of the spheres covering a capsule.
SPHERE_SPACING = 0.02


@dataclass(frozen=True, eq=False)
class BodyPolytope:
    """``{x : normals @ x <= offsets}`` in body ``body``'s frame (m)."""

    body: int
    normals: np.ndarray   # (K, 3)
    offsets: np.ndarray   # (K,)


def geom_support(m: mujoco.MjModel, g: int, dirs: np.ndarray, vertices: np.ndarray | None) -> np.ndarray:
    """Support ``max_{x in geom} d . x`` (m) of geom ``g`` in its body's frame for each row of
    ``dirs`` (K, 3); ``vertices``: a mesh geom's hull vertices in the body frame (else None)."""
    if vertices is not None:
        return (vertices @ dirs.T).max(axis=0)
    rot = quat_to_mat_np(m.geom_quat[g])
    local = dirs @ rot                           # the directions in the geom's frame
    size = m.geom_size[g]
    base = dirs @ m.geom_pos[g]
    t = int(m.geom_type[g])
    if t == mujoco.mjtGeom.mjGEOM_SPHERE:
        return base + size[0]
    if t == mujoco.mjtGeom.mjGEOM_CAPSULE:
        return base + size[1] * np.abs(local[:, 2]) + size[0]
    if t == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return base + size[1] * np.abs(local[:, 2]) + size[0] * np.sqrt(np.maximum(0.0, 1 - local[:, 2] ** 2))
    if t == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        return base + np.linalg.norm(local * size, axis=1)
    if t == mujoco.mjtGeom.mjGEOM_BOX:
        return base + np.abs(local) @ size
    # anything else: its bounding box (geom_aabb: centre and half-extents in the geom's frame)
    centre, half = m.geom_aabb[g, :3], m.geom_aabb[g, 3:]
    return base + local @ centre + np.abs(local) @ half


def body_polytope(m: mujoco.MjModel, body: int, geoms: list[tuple[int, np.ndarray | None]]) -> BodyPolytope:
    """The 14-DOP of ``geoms`` ((geom id, mesh hull vertices or None) of ``body``)."""
    h = np.max([geom_support(m, g, DIRECTIONS, v) for g, v in geoms], axis=0)
    return BodyPolytope(body, DIRECTIONS.copy(), h)


def sphere_cover(p0: np.ndarray, p1: np.ndarray, radius: float) -> tuple[np.ndarray, float]:
    """Parameters (n,) in [0, 1] of the spheres covering the capsule p0-p1 (see the module
    docstring) and their radius (m)."""
    length = float(np.linalg.norm(np.asarray(p1) - np.asarray(p0)))
    n = max(1, int(np.ceil(length / SPHERE_SPACING))) + 1
    s = length / (n - 1)
    return np.linspace(0.0, 1.0, n), float(np.sqrt(radius * radius + s * s / 4))


def clearance_np(poly: BodyPolytope, pose: tuple[np.ndarray, np.ndarray], a: np.ndarray, b: np.ndarray,
                 radius: float) -> float:
    """Clearance (m) of capsule a-b (world, m) from the polytope whose body is at ``pose`` =
    (position (3,), rotation (3, 3))."""
    ts, r = sphere_cover(a, b, radius)
    pos, rot = pose
    pts = (a + ts[:, None] * (b - a) - pos) @ rot      # body frame
    return float(np.min(np.max(pts @ poly.normals.T - poly.offsets, axis=1)) - r)


def clearance_sx(poly: BodyPolytope, origin, axes, a, b, length: float, radius: float):
    """Symbolic clearance (m) of each covering sphere of the capsule with world ends ``a``, ``b``
    (casadi 3-vectors), segment ``length`` and ``radius`` (m) from the polytope, as a column:
    one row per sphere, so that a projection step sees every sphere inside at once (with only the
    deepest one, each step pushes one sphere out and the next one in turn becomes the deepest).
    ``origin`` is the body's world position and ``axes`` its three world axis vectors."""
    ts, r = sphere_cover(np.zeros(3), np.array([length, 0.0, 0.0]), radius)
    la = [ca.dot(e, a - origin) for e in axes]           # the segment in the body frame
    ld = [ca.dot(e, b - a) for e in axes]

    def along(n, v):
        return sum(float(n[i]) * v[i] for i in range(3) if n[i] != 0.0)

    faces = [(along(n, la) - float(h), along(n, ld)) for n, h in zip(poly.normals, poly.offsets)]
    rows = []
    for t in ts:  # a sphere centre's face values are linear along the segment
        best = None
        for base, slope in faces:
            v = base + float(t) * slope if t else base
            best = v if best is None else ca.fmax(best, v)
        rows.append(best - r)
    return ca.vertcat(*rows)

"""Geometry of a compiled MuJoCo model at one pose, for drafting robot configs.

Pure functions of ``(model, data)`` after ``mj_kinematics``: world frame, metres, z up.
"""

from __future__ import annotations

import mujoco
import numpy as np

_GEOM = mujoco.mjtGeom


def axes_center(points: np.ndarray, dirs: np.ndarray, prior: np.ndarray, reg: float = 1e-6) -> np.ndarray:
    """The point nearest (least squares) to the lines ``points[i] + t * dirs[i]`` (world, m).

    ``prior`` (3,) breaks ties along directions the lines leave free (one line, parallel lines):
    a term ``reg * |p - prior|^2`` is added."""
    a = reg * np.eye(3)
    b = reg * np.asarray(prior, float)
    for p, d in zip(np.asarray(points, float), np.asarray(dirs, float)):
        d = d / np.linalg.norm(d)
        proj = np.eye(3) - np.outer(d, d)
        a += proj
        b += proj @ p
    return np.linalg.solve(a, b)


def hinge_axes(model: mujoco.MjModel, data: mujoco.MjData, bodies: list[int]) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """Anchor points (k, 3), axis directions (k, 3) and joint ids of the hinges on ``bodies``."""
    pts, dirs, ids = [], [], []
    for j in range(model.njnt):
        if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE and int(model.jnt_bodyid[j]) in bodies:
            pts.append(data.xanchor[j].copy())
            dirs.append(data.xaxis[j].copy())
            ids.append(j)
    return np.array(pts).reshape(-1, 3), np.array(dirs).reshape(-1, 3), ids


def to_body(data: mujoco.MjData, body: int, world_point: np.ndarray) -> np.ndarray:
    """A world point expressed in ``body``'s frame."""
    return data.xmat[body].reshape(3, 3).T @ (np.asarray(world_point, float) - data.xpos[body])


#: The geom group MuJoCo Menagerie models put their collision geoms in.
COLLISION_GROUP = 3


def is_collision(model: mujoco.MjModel, g: int) -> bool:
    """Whether geom ``g`` is collision geometry: contype or conaffinity set; in a model that sets
    them on no geom at all (collisions by explicit pairs, or collision geoms marked by class), a
    geom of an explicit ``<pair>`` or of group :data:`COLLISION_GROUP`."""
    if model.geom_contype.any() or model.geom_conaffinity.any():
        return bool(model.geom_contype[g] or model.geom_conaffinity[g])
    return bool(model.geom_group[g] == COLLISION_GROUP or g in model.pair_geom1 or g in model.pair_geom2)


def body_geoms(model: mujoco.MjModel, body: int, collision_only: bool = True) -> list[int]:
    gs = [g for g in range(model.ngeom) if model.geom_bodyid[g] == body]
    return [g for g in gs if is_collision(model, g)] if collision_only else gs


def geom_points(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> np.ndarray:
    """World points on geom ``g`` that include its lowest ones: sphere and capsule bottoms, box
    corners, mesh vertices, cylinder rims, ellipsoid bottom; other types: bounding-box corners."""
    t = model.geom_type[g]
    c = data.geom_xpos[g]
    rot = data.geom_xmat[g].reshape(3, 3)
    size = model.geom_size[g]
    down = np.array([0.0, 0.0, -1.0])
    if t == _GEOM.mjGEOM_SPHERE:
        return (c + size[0] * down)[None]
    if t == _GEOM.mjGEOM_CAPSULE:
        ends = np.array([c + rot[:, 2] * size[1], c - rot[:, 2] * size[1]])
        return ends + size[0] * down
    if t == _GEOM.mjGEOM_BOX:
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
        return c + (signs * size[:3]) @ rot.T
    if t == _GEOM.mjGEOM_MESH:
        mid = model.geom_dataid[g]
        v = model.mesh_vert[model.mesh_vertadr[mid]: model.mesh_vertadr[mid] + model.mesh_vertnum[mid]]
        return c + v @ rot.T
    if t == _GEOM.mjGEOM_CYLINDER:
        ang = np.linspace(0, 2 * np.pi, 24, endpoint=False)
        rim = np.stack([np.cos(ang), np.sin(ang), np.zeros_like(ang)], 1) * size[0]
        pts = [rim + [0, 0, h] for h in (-size[1], size[1])]
        return c + np.concatenate(pts) @ rot.T
    if t == _GEOM.mjGEOM_ELLIPSOID:
        return (c + down * np.sqrt(np.sum((rot[2] * size[:3]) ** 2)))[None]
    return aabb_corners(model, data, g)


def aabb_corners(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> np.ndarray:
    """The 8 world corners of geom ``g``'s bounding box (which is in the geom frame)."""
    center, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
    rot = data.geom_xmat[g].reshape(3, 3)
    return data.geom_xpos[g] + (center + signs * half) @ rot.T


def sole_frame(data: mujoco.MjData, body: int) -> np.ndarray:
    """(3, 3) rotation of the sole frame in ``body``'s frame: z the world's up, x the world's
    forward (+x) laid into the floor plane (the body's own axes when they are already so)."""
    rot = data.xmat[body].reshape(3, 3)
    up = rot.T @ np.array([0.0, 0.0, 1.0])
    fwd = rot.T @ np.array([1.0, 0.0, 0.0])
    fwd = fwd - (fwd @ up) * up
    if np.linalg.norm(fwd) < 1e-6:
        fwd = np.array([1.0, 0.0, 0.0]) - up[0] * up
    fwd /= np.linalg.norm(fwd)
    return np.stack([fwd, np.cross(up, fwd), up], axis=1)


def mat_to_quat(rot: np.ndarray) -> np.ndarray:
    """wxyz quaternion of a rotation matrix (w >= 0)."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(rot, dtype=float).ravel())
    return q if q[0] >= 0 else -q


def sole_rectangle(model: mujoco.MjModel, data: mujoco.MjData, body: int, geoms: list[int],
                   tol: float = 0.005) -> tuple[np.ndarray, np.ndarray, int, np.ndarray]:
    """Sole of a foot: the rectangle covering the points of ``geoms`` within ``tol`` (m) of their
    lowest point, in the floor plane at the current pose whatever the body's axes
    (:func:`sole_frame`). Returns (centre (3,) in ``body``'s frame, half extents (2,) along the
    sole frame's x and y, point count, sole frame rotation (3, 3) in the body frame)."""
    pts = np.concatenate([geom_points(model, data, g) for g in geoms])
    low = pts[pts[:, 2] <= pts[:, 2].min() + tol]
    frame = sole_frame(data, body)
    local = np.array([to_body(data, body, p) for p in low]) @ frame  # sole-frame coordinates
    lo, hi = local.min(0), local.max(0)
    z = float(to_body(data, body, pts[np.argmin(pts[:, 2])]) @ frame[:, 2])
    centre = frame @ np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, z])
    return centre, (hi[:2] - lo[:2]) / 2, len(low), frame

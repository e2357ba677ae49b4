"""Forward kinematics in casadi, built from a MuJoCo model's kinematic tree.

Nothing here is written per robot: the tree is walked from ``body_parentid``, ``body_pos``,
``body_quat``, ``body_ipos``, ``jnt_axis``, ``jnt_pos`` and ``site_pos``, exactly as MuJoCo's
``mj_kinematics`` does (free root joint, then hinges about their anchors). The expressions are
casadi ``SX`` (or ``MX``) so they can be differentiated, mapped over frames and code-generated.

Frames: world z up; positions in metres; the root quaternion is **wxyz** (normalised here, as
MuJoCo does); hinge angles in radians in model order.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import mujoco
import numpy as np

_FREE = mujoco.mjtJoint.mjJNT_FREE
_HINGE = mujoco.mjtJoint.mjJNT_HINGE


def quat_to_mat_np(q: np.ndarray) -> np.ndarray:
    """(..., 4) wxyz unit quaternions -> (..., 3, 3) rotation matrices."""
    q = np.asarray(q, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def quat_to_mat_sym(q: Any) -> Any:
    """A casadi wxyz quaternion (4,) -> 3x3 rotation matrix (normalised first)."""
    q = q / ca.norm_2(q)
    w, x, y, z = q[0], q[1], q[2], q[3]
    return ca.vertcat(
        ca.horzcat(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        ca.horzcat(2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        ca.horzcat(2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    )


def axis_angle_sym(axis: np.ndarray, angle: Any) -> Any:
    """Rotation matrix about a constant unit ``axis`` by a symbolic ``angle`` (Rodrigues)."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return ca.DM(np.eye(3)) + ca.sin(angle) * ca.DM(k) + (1 - ca.cos(angle)) * ca.DM(k @ k)


@dataclass(frozen=True)
class Frames:
    """World poses of every body: ``pos[b]`` (3x1) and ``rot[b]`` (3x3), casadi expressions; for
    every hinge (index in model order) its world ``axis`` and ``anchor``; ``hinges_of[b]``: the
    hinges between the root and body ``b`` (inclusive)."""

    pos: list
    rot: list
    axis: dict = field(default_factory=dict)
    anchor: dict = field(default_factory=dict)
    hinges_of: list = field(default_factory=list)


def body_frames(model: mujoco.MjModel, root_pos: Any, root_rot: Any, hinges: Any) -> Frames:
    """World frames of all bodies for root position ``root_pos`` (3,), root rotation matrix
    ``root_rot`` (3x3) and hinge angles ``hinges`` (n,) in model order (casadi expressions).

    Mirrors ``mj_kinematics``: body frame = parent frame * (body_pos, body_quat); each hinge
    rotates the body about its axis through its anchor ``jnt_pos`` (body frame); a free joint sets
    the body's world pose directly.
    """
    nb = model.nbody
    pos: list = [None] * nb
    rot: list = [None] * nb
    pos[0] = ca.DM.zeros(3, 1)
    rot[0] = ca.DM(np.eye(3))
    axes, anchors, hinges_of = {}, {}, [[] for _ in range(nb)]
    for b in range(1, nb):
        p = int(model.body_parentid[b])
        rb = ca.DM(quat_to_mat_np(model.body_quat[b]))
        xpos = pos[p] + ca.mtimes(rot[p], ca.DM(model.body_pos[b]))
        xrot = ca.mtimes(rot[p], rb)
        hinges_of[b] = list(hinges_of[p])
        for j in range(int(model.body_jntadr[b]), int(model.body_jntadr[b] + model.body_jntnum[b])):
            jt = model.jnt_type[j]
            if jt == _FREE:
                xpos, xrot = root_pos, root_rot
            elif jt == _HINGE:
                h = int(model.jnt_qposadr[j]) - 7
                anchor = ca.DM(model.jnt_pos[j])
                xanchor = xpos + ca.mtimes(xrot, anchor)
                axes[h] = ca.mtimes(xrot, ca.DM(np.asarray(model.jnt_axis[j]) / np.linalg.norm(model.jnt_axis[j])))
                anchors[h] = xanchor
                hinges_of[b].append(h)
                xrot = ca.mtimes(xrot, axis_angle_sym(model.jnt_axis[j], hinges[h]))
                xpos = xanchor - ca.mtimes(xrot, anchor)
            else:  # the loader refuses other joint types
                raise ValueError(f"joint {j}: only free and hinge joints are supported")
        pos[b], rot[b] = xpos, xrot
    return Frames(pos, rot, axes, anchors, hinges_of)


class TangentFrames:
    """Body frames at ``qpos`` and their first-order change under a tangent step ``dx`` = (root
    translation (3), root-local rotation vector (3), hinge increments (n)), written with the
    geometric Jacobian (joint axis x lever arm) instead of differentiating the whole chain: the
    value and the Jacobian with respect to ``dx`` at ``dx = 0`` are exact, and cheap."""

    def __init__(self, model: mujoco.MjModel, qpos: Any, dx: Any):
        self.model = model
        self.root_rot = quat_to_mat_sym(qpos[3:7])
        self.frames = body_frames(model, qpos[0:3], self.root_rot, qpos[7:])
        self.root = int(model.jnt_bodyid[0])
        self.dx = dx
        self._omega: dict[int, Any] = {}

    def omega(self, body: int) -> Any:
        """Angular change of ``body`` (3x1, linear in dx)."""
        if body not in self._omega:
            fr, dx = self.frames, self.dx
            w = ca.mtimes(self.root_rot, dx[3:6])
            for h in fr.hinges_of[body]:
                w = w + dx[6 + h] * fr.axis[h]
            self._omega[body] = w
        return self._omega[body]

    def point(self, body: int, offset: np.ndarray) -> Any:
        """World position of a point fixed in ``body``, to first order in dx."""
        fr, dx = self.frames, self.dx
        p0 = point_in_body(fr, body, offset)
        dp = dx[0:3] + ca.cross(ca.mtimes(self.root_rot, dx[3:6]), p0 - fr.pos[self.root])
        for h in fr.hinges_of[body]:
            dp = dp + dx[6 + h] * ca.cross(fr.axis[h], p0 - fr.anchor[h])
        return p0 + dp

    def vector(self, body: int, local: np.ndarray) -> Any:
        """World direction of a vector fixed in ``body``, to first order in dx."""
        v0 = ca.mtimes(self.frames.rot[body], ca.DM(np.asarray(local, dtype=np.float64)))
        return v0 + ca.cross(self.omega(body), v0)


def point_in_body(frames: Frames, body: int, offset: np.ndarray) -> Any:
    """World position of a point fixed at ``offset`` (m) in body ``body``'s frame."""
    return frames.pos[body] + ca.mtimes(frames.rot[body], ca.DM(np.asarray(offset, dtype=np.float64)))


def site_position(model: mujoco.MjModel, frames: Frames, site: int) -> Any:
    """World position of site ``site`` (3x1)."""
    return point_in_body(frames, int(model.site_bodyid[site]), model.site_pos[site])


def center_of_mass(model: mujoco.MjModel, frames: Frames, root_body: int = 1) -> Any:
    """Centre of mass (3x1) of the subtree under ``root_body``: sum m_i * xipos_i / M."""
    bodies = [b for b in range(1, model.nbody) if _under(model, b, root_body) and model.body_mass[b] > 0]
    total = float(sum(model.body_mass[b] for b in bodies))
    acc = ca.DM.zeros(3, 1)
    for b in bodies:
        acc = acc + float(model.body_mass[b]) * point_in_body(frames, b, model.body_ipos[b])
    return acc / total


def _under(model: mujoco.MjModel, body: int, root: int) -> bool:
    while body > 0:
        if body == root:
            return True
        body = int(model.body_parentid[body])
    return False


def frames_from_qpos(model: mujoco.MjModel, qpos: Any) -> Frames:
    """Body frames for a full ``qpos`` (7 + n): root xyz, root wxyz, hinges."""
    return body_frames(model, qpos[0:3], quat_to_mat_sym(qpos[3:7]), qpos[7:])


def fk_function(model: mujoco.MjModel, root_body: int = 1) -> ca.Function:
    """``fk(qpos) -> (xpos (3, nbody), xmat (9, nbody) row-major, site_xpos (3, nsite), com (3, 1))``,
    the same quantities as MuJoCo's ``data.xpos``, ``data.xmat``, ``data.site_xpos`` and
    ``data.subtree_com[root_body]``; used to check the casadi tree against MuJoCo."""
    q = ca.SX.sym("qpos", model.nq)
    fr = frames_from_qpos(model, q)
    xpos = ca.horzcat(*fr.pos)
    xmat = ca.horzcat(*[ca.reshape(r.T, 9, 1) for r in fr.rot])
    sites = ca.horzcat(*[site_position(model, fr, s) for s in range(model.nsite)]) if model.nsite else ca.SX.zeros(3, 0)
    com = center_of_mass(model, fr, root_body)
    return ca.Function("fk", [q], [xpos, xmat, sites, com], ["qpos"], ["xpos", "xmat", "site_xpos", "com"])

"""Per-frame kinematics of a RobotMotion, computed once and shared by every check.

One ``MjData`` on the :func:`~motion2robot.validate.models.check_model`; per frame:
``mj_kinematics``, ``mj_comPos``, ``mj_comVel``, ``mj_rne`` (rigid-body inverse dynamics
M(q) qacc + c(q, qvel), gravity included) and ``mj_collision``. Velocities and accelerations come
from central finite differences of qpos (the free root's angular velocity from quaternion
differences, in the root's local frame, as MuJoCo's ``mj_differentiatePos`` does).

Units: metres, radians, seconds, newtons; world frame z up.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate import kinematics_kernel
from motion2robot.validate.models import check_model


@dataclass(frozen=True, eq=False)
class Contacts:
    """All contacts found over the motion: K rows of (frame, geom1, geom2, dist (m, < 0 = penetration))."""

    frame: np.ndarray
    geom1: np.ndarray
    geom2: np.ndarray
    dist: np.ndarray


@dataclass(frozen=True, eq=False)
class Kinematics:
    """Trajectory-wide kinematic and dynamic quantities (T frames).

    qpos (T, nq); qvel, qacc (T, nv) (root linear part in world frame, angular part in the root
    frame); corners (T, 2, 4, 3) sole corner positions [left, right]; corner_vel (T, 2, 4, 3);
    com (T, 3); rne (T, nv) generalised force M qacc + c (N, N*m); xanchor, xaxis (T, n, 3) hinge
    anchors and unit axes in world; root_xmat (T, 3, 3); torso_pos (T, 3), torso_up (T, 3) the
    torso body's z axis; contacts: every contact of the check model.
    """

    model: mujoco.MjModel
    fps: float
    qpos: np.ndarray
    qvel: np.ndarray
    qacc: np.ndarray
    corners: np.ndarray
    corner_vel: np.ndarray
    com: np.ndarray
    rne: np.ndarray
    xanchor: np.ndarray
    xaxis: np.ndarray
    root_xmat: np.ndarray
    torso_pos: np.ndarray
    torso_up: np.ndarray
    contacts: Contacts

    @property
    def num_frames(self) -> int:
        return int(self.qpos.shape[0])

    @property
    def time(self) -> np.ndarray:
        return np.arange(self.num_frames) / self.fps


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of (..., 4) wxyz quaternions."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ], axis=-1)


def quat_to_rotvec(q: np.ndarray) -> np.ndarray:
    """(..., 4) wxyz unit quaternions -> (..., 3) rotation vectors (rad), shortest way round."""
    q = np.where(q[..., :1] < 0, -q, q)
    v = q[..., 1:]
    s = np.linalg.norm(v, axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(s, q[..., :1])
    scale = np.where(s > 1e-12, angle / np.maximum(s, 1e-12), 2.0)
    return v * scale


def differentiate(qpos: np.ndarray, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """Central finite differences of a (T, 7 + n) free-root trajectory -> (qvel, qacc), (T, 6 + n).

    Root linear velocity in world; root angular velocity in the root frame; one-sided at the ends
    (T = 1 gives zeros)."""
    T = qpos.shape[0]
    nv = qpos.shape[1] - 1
    if T < 2:
        return np.zeros((T, nv)), np.zeros((T, nv))
    dt = 1.0 / fps
    mid = np.empty((T - 1, nv))  # velocities at t + 1/2
    mid[:, :3] = np.diff(qpos[:, :3], axis=0) / dt
    q = qpos[:, 3:7] / np.linalg.norm(qpos[:, 3:7], axis=1, keepdims=True)
    conj = q[:-1] * np.array([1.0, -1.0, -1.0, -1.0])
    mid[:, 3:6] = quat_to_rotvec(quat_mul(conj, q[1:])) / dt
    mid[:, 6:] = np.diff(qpos[:, 7:], axis=0) / dt
    qvel = np.empty((T, nv))
    qvel[1:-1] = 0.5 * (mid[:-1] + mid[1:])
    qvel[0], qvel[-1] = mid[0], mid[-1]
    qacc = np.zeros((T, nv))
    if T >= 3:
        qacc[1:-1] = np.diff(mid, axis=0) / dt
        qacc[0], qacc[-1] = qacc[1], qacc[-2]
    return qvel, qacc


def compute_kinematics(motion: RobotMotion, robot: Robot, *, collisions: bool = True) -> Kinematics:
    """Run the per-frame MuJoCo pass over ``motion`` (whose qpos layout must match ``robot``);
    ``collisions=False`` skips ``mj_collision`` (no contacts: for callers that need the rest)."""
    m = check_model(robot)
    d = mujoco.MjData(m)
    qpos = np.ascontiguousarray(motion.qpos, dtype=np.float64)
    T = qpos.shape[0]
    qvel, qacc = differentiate(qpos, motion.fps)
    jids = np.asarray(robot.joint_ids)
    sole = np.asarray(robot.sole_sites).ravel()
    root, torso = int(robot.root_body), int(robot.torso_body)

    site_xpos = np.empty((T, m.nsite, 3))
    xanchor = np.empty((T, m.njnt, 3))
    xaxis = np.empty((T, m.njnt, 3))
    subtree_com = np.empty((T, m.nbody, 3))
    xpos = np.empty((T, m.nbody, 3))
    xmat = np.empty((T, m.nbody, 9))
    rne = np.empty((T, m.nv))
    native = kinematics_kernel.run(m, d, qpos, qvel, qacc, collisions, (site_xpos, xanchor, xaxis, subtree_com, xpos,
                                                                       xmat, rne))
    contacts = None if native is None else Contacts(native[0], native[1][:, 0].copy(), native[1][:, 1].copy(), native[2])
    if contacts is None:
        contacts = _frame_loop(m, d, qpos, qvel, qacc, collisions, site_xpos, xanchor, xaxis, subtree_com, xpos, xmat, rne)
    corners = site_xpos[:, sole].reshape(T, 2, 4, 3)
    corner_vel = np.gradient(corners, 1.0 / motion.fps, axis=0) if T > 1 else np.zeros_like(corners)
    return Kinematics(
        model=m, fps=float(motion.fps), qpos=qpos, qvel=qvel, qacc=qacc, corners=corners,
        corner_vel=corner_vel, com=subtree_com[:, root], rne=rne, xanchor=xanchor[:, jids], xaxis=xaxis[:, jids],
        root_xmat=xmat[:, root].reshape(T, 3, 3), torso_pos=xpos[:, torso], torso_up=xmat[:, torso][:, [2, 5, 8]],
        contacts=contacts,
    )


def _frame_loop(m: mujoco.MjModel, d: mujoco.MjData, qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray,
                collisions: bool, site_xpos: np.ndarray, xanchor: np.ndarray, xaxis: np.ndarray,
                subtree_com: np.ndarray, xpos: np.ndarray, xmat: np.ndarray, rne: np.ndarray) -> Contacts:
    """The per-frame pass in Python (without the compiled loop of :mod:`.kinematics_kernel`, the
    same numbers): fills the (T, ...) arrays, returns the contacts."""
    T = len(qpos)
    con_frames, con_geom, con_dist = [], [], []
    kin, com_pos, com_vel, rne_fn, collide = (
        mujoco.mj_kinematics, mujoco.mj_comPos, mujoco.mj_comVel, mujoco.mj_rne, mujoco.mj_collision)
    # views into MjData bound once (the buffers do not move), to keep Python out of the loop
    d_qpos, d_qvel, d_qacc = d.qpos, d.qvel, d.qacc
    d_site, d_anchor, d_axis, d_com, d_xpos, d_xmat = d.site_xpos, d.xanchor, d.xaxis, d.subtree_com, d.xpos, d.xmat
    for t in range(T):
        d_qpos[:] = qpos[t]
        d_qvel[:] = qvel[t]
        d_qacc[:] = qacc[t]
        kin(m, d)
        com_pos(m, d)
        com_vel(m, d)
        rne_fn(m, d, 1, rne[t])
        if collisions:
            collide(m, d)
        site_xpos[t] = d_site
        xanchor[t] = d_anchor
        xaxis[t] = d_axis
        subtree_com[t] = d_com
        xpos[t] = d_xpos
        xmat[t] = d_xmat
        if d.ncon:
            con = d.contact
            con_frames.append(t)
            con_geom.append(con.geom.copy())
            con_dist.append(con.dist.copy())
    if con_geom:
        counts = [len(x) for x in con_dist]
        geom = np.concatenate(con_geom).astype(np.int64)
        return Contacts(np.repeat(np.asarray(con_frames, dtype=np.int64), counts), geom[:, 0].copy(),
                        geom[:, 1].copy(), np.concatenate(con_dist))
    return Contacts(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))

"""Joint torques by inverse dynamics, with the ground reaction spread over the soles in contact.

Method (per frame, vectorised over the trajectory):

1. ``mj_rne`` gives the generalised force tau = M(q) qacc + c(q, qvel) (gravity included) that
   would produce the finite-difference accelerations (:mod:`~motion2robot.validate.kinematics`).
2. Its 6 free-root rows are the wrench the world must supply: force F (world) and moment
   R tau_rot about the root origin. Only the floor can supply it: a normal force f_i >= 0 at
   each supporting sole corner, and per foot a tangential (friction) force (f_x, f_y) at the sole
   centre and a friction moment m_z about the vertical: 8 + 6 = 14 unknowns u with A u = wrench
   (A: the 6 x 14 root rows of J_c^T).
3. The system is statically indeterminate (two feet, four corners each), so among the solutions
   we take the one a torque-minimising controller would use: minimise the squared hinge torques
   ||tau_h - J_h u||^2 plus a small regularisation of u (tangential components cost
   ``TANGENTIAL_COST`` times more than normal ones, keeping friction demands low), with the
   normal forces kept non-negative by an active set (corners that would pull are dropped and the
   frame re-solved). The wrench equality is a stiff quadratic penalty, so each pass is one batched
   14 x 14 solve per frame, and a wrench the floor cannot supply (flight, ZMP outside the
   support) is met in the least-squares sense, its remainder reported as a residual. The torques
   are therefore close to the least any contact distribution needs: a joint over its limit here
   is over it for every controller.
4. Hinge torques are tau_h - J_h u with the hinge rows of the contact Jacobian: for hinge j on
   the path to the foot (axis a_j, anchor o_j in world), a point force f at p contributes
   a_j . ((p - o_j) x f) and a vertical moment m_z contributes a_j,z m_z. Optionally the servo's
   own reflected inertia and damping (the MJCF's armature * qacc + damping * qvel) are added: the
   damping of a servo model is its speed-torque slope, so this is the torque the motor must make.

The multi-body ZMP follows from the same root wrench: the floor point where the required moment
has no horizontal component.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2robot.robot.robot import Robot
from motion2robot.validate.kinematics import Kinematics

#: Cost of a tangential unit force relative to a normal one in the force regularisation.
TANGENTIAL_COST = 100.0
#: Weight of the force regularisation relative to the hinge torques, per squared robot height (m^2).
REGULARISATION = 1e-3
#: Weight of the root-wrench equality (penalty), per squared robot height (m^2).
PENALTY = 1e6
#: Active-set passes for the non-negative normal forces.
ACTIVE_SET_ITERATIONS = 8
#: A frame whose required vertical force is below this fraction of m*g has no defined ZMP.
MIN_NORMAL_FRACTION = 0.05


@dataclass(frozen=True, eq=False)
class Dynamics:
    """tau (T, n) hinge torques (N*m) in ``joint_names`` order, of which servo_tau (T, n) is the
    servo's own armature * qacc + damping * qvel (zero without servo dynamics); normal (T, 2, 4) corner normal
    forces (N); friction (T, 2, 3) per foot (f_x, f_y (N), m_z (N*m)); residual (T, 6) unsupplied
    root wrench [force; moment about the root] (world); zmp_xy (T, 2) (NaN where undefined);
    normal_force (T,) total required vertical force (N)."""

    tau: np.ndarray
    servo_tau: np.ndarray
    normal: np.ndarray
    friction: np.ndarray
    residual: np.ndarray
    zmp_xy: np.ndarray
    normal_force: np.ndarray


def foot_ancestor_mask(robot: Robot) -> np.ndarray:
    """(n, 2) bool: hinge j moves foot k (lies on the path from the root to that foot)."""
    m = robot.model
    jbody = m.jnt_bodyid[np.asarray(robot.joint_ids)]
    out = np.zeros((robot.n_joints, 2), dtype=bool)
    for k, foot in enumerate(np.asarray(robot.foot_bodies)):
        chain = set()
        b = int(foot)
        while b > 0:
            chain.add(b)
            b = int(m.body_parentid[b])
        out[:, k] = [int(b) in chain for b in jbody]
    return out


def contact_rows(kin: Kinematics, robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """(A (T, 6, 14), J (T, n, 14)): root rows and hinge rows of the 14 contact unknowns
    [f_z of the 8 corners (left 0-3, right 0-3); f_x, f_y, m_z left; f_x, f_y, m_z right]."""
    T, n = kin.num_frames, robot.n_joints
    p = kin.corners.reshape(T, 8, 3)
    c = kin.corners.mean(axis=2)  # (T, 2, 3) sole centres
    d = p - kin.qpos[:, None, :3]
    dc = c - kin.qpos[:, None, :3]
    A = np.zeros((T, 6, 14))
    A[:, 2, :8] = 1.0
    A[:, 3, :8], A[:, 4, :8] = d[..., 1], -d[..., 0]  # (p - x) x e_z
    for k in range(2):
        ix, iy, iz = 8 + 3 * k, 9 + 3 * k, 10 + 3 * k
        A[:, 0, ix] = 1.0
        A[:, 4, ix], A[:, 5, ix] = dc[:, k, 2], -dc[:, k, 1]  # (c - x) x e_x
        A[:, 1, iy] = 1.0
        A[:, 3, iy], A[:, 5, iy] = -dc[:, k, 2], dc[:, k, 0]  # (c - x) x e_y
        A[:, 5, iz] = 1.0
    a, o = kin.xaxis, kin.xanchor  # (T, n, 3)
    mask = foot_ancestor_mask(robot).astype(float)  # (n, 2)
    J = np.zeros((T, n, 14))
    # (a x (p - o))_z = a_x p_y - a_y p_x - (a_x o_y - a_y o_x)
    az_o = a[..., 0] * o[..., 1] - a[..., 1] * o[..., 0]  # (T, n)
    J[..., :8] = a[..., 0, None] * p[:, None, :, 1] - a[..., 1, None] * p[:, None, :, 0] - az_o[..., None]
    J[..., :8] *= np.repeat(mask, 4, axis=1)
    for k in range(2):
        rc = c[:, None, k, :] - o  # (T, n, 3)
        J[..., 8 + 3 * k] = (a[..., 1] * rc[..., 2] - a[..., 2] * rc[..., 1]) * mask[:, k]
        J[..., 9 + 3 * k] = (a[..., 2] * rc[..., 0] - a[..., 0] * rc[..., 2]) * mask[:, k]
        J[..., 10 + 3 * k] = a[..., 2] * mask[:, k]
    return A, J


def distribute_contact_forces(A: np.ndarray, J: np.ndarray, support: np.ndarray, wrench: np.ndarray,
                              bias: np.ndarray, weights: np.ndarray, penalty: float) -> np.ndarray:
    """Contact unknowns u (T, 14) (see :func:`contact_rows`) minimising
    ||bias - J u||^2 + u' diag(weights) u + penalty ||A u - wrench||^2 with u_i = 0 for corners not
    in ``support`` (T, 8), friction of a foot without support zero, and corner normals >= 0."""
    T = A.shape[0]
    M = np.concatenate([J, np.sqrt(penalty) * A], axis=1)
    Mt = M.transpose(0, 2, 1)
    H = Mt @ M + np.diag(weights)
    g = (Mt @ np.concatenate([bias, np.sqrt(penalty) * wrench], axis=1)[..., None])[..., 0]
    act = support.copy()
    u = np.zeros((T, 14))
    idx = np.flatnonzero(act.any(axis=1))
    diag = np.arange(14)
    for _ in range(ACTIVE_SET_ITERATIONS):
        if idx.size == 0:
            break
        a = act[idx]
        m = np.concatenate([a, np.repeat(a.reshape(-1, 2, 4).any(axis=2), 3, axis=1)], axis=1).astype(float)
        K = H[idx] * m[:, :, None] * m[:, None, :]
        K[:, diag, diag] += 1.0 - m
        u[idx] = np.linalg.solve(K, (g[idx] * m)[..., None])[..., 0]
        pulling = a & (u[idx, :8] < -1e-6)
        rows = pulling.any(axis=1)
        act[idx[rows]] &= ~pulling[rows]
        idx = idx[rows]
    u[:, :8] = np.where(act, np.maximum(u[:, :8], 0.0), 0.0)
    has = np.repeat(act.reshape(T, 2, 4).any(axis=2), 3, axis=1)
    u[:, 8:] = np.where(has, u[:, 8:], 0.0)
    return u


def inverse_dynamics(kin: Kinematics, robot: Robot, support: np.ndarray, *,
                     servo_dynamics: bool = True) -> Dynamics:
    """Hinge torques and contact forces for the trajectory in ``kin``.

    support: (T, 2, 4) bool sole corners that may push on the floor."""
    T = kin.num_frames
    root_pos = kin.qpos[:, :3]
    moment_root = (kin.root_xmat @ kin.rne[:, 3:6, None])[..., 0]
    wrench = np.concatenate([kin.rne[:, :3], moment_root], axis=1)
    A, J = contact_rows(kin, robot)
    h2 = max(robot.height, 1e-3) ** 2
    half = [max(f.sole_half[0], 1e-3) for f in robot.config.feet]
    w = np.concatenate([np.ones(8)] + [[TANGENTIAL_COST, TANGENTIAL_COST, TANGENTIAL_COST / half[k] ** 2] for k in range(2)])
    u = distribute_contact_forces(A, J, support.reshape(T, 8), wrench, kin.rne[:, 6:],
                                  REGULARISATION * h2 * w, PENALTY * h2)
    tau = kin.rne[:, 6:] - (J @ u[..., None])[..., 0]
    residual = wrench - (A @ u[..., None])[..., 0]
    servo = np.zeros_like(tau)
    if servo_dynamics:
        m = robot.model
        dofs = m.jnt_dofadr[np.asarray(robot.joint_ids)]
        servo = m.dof_armature[dofs] * kin.qacc[:, 6:] + m.dof_damping[dofs] * kin.qvel[:, 6:]
        tau = tau + servo
    # ZMP: moment about the world origin of the required wrench, zero horizontal moment at z = 0
    N0 = np.cross(root_pos, wrench[:, :3]) + moment_root
    Fz = wrench[:, 2]
    ok = Fz > MIN_NORMAL_FRACTION * robot.mass * 9.81
    safe = np.where(ok, Fz, 1.0)
    zmp = np.stack([-N0[:, 1] / safe, N0[:, 0] / safe], axis=1)
    zmp[~ok] = np.nan
    return Dynamics(tau=tau, servo_tau=servo, normal=u[:, :8].reshape(T, 2, 4), friction=u[:, 8:].reshape(T, 2, 3),
                    residual=residual, zmp_xy=zmp, normal_force=Fz)

"""Joint torques by inverse dynamics, with a floor reaction that could really happen.

Method (per frame, vectorised over the trajectory):

1. ``mj_rne`` gives the generalised force tau = M(q) qacc + c(q, qvel) (gravity included) that
   would produce the finite-difference accelerations (:mod:`~motion2robot.validate.kinematics`).
2. Its 6 free-root rows are the wrench the world must supply: force F (world) and moment
   R tau_rot about the root origin. Only the floor can supply it, through the supporting sole
   corners: a force per corner inside the friction cone (mu from the model's floor and sole geoms),
   which keeps each foot's centre of pressure on its sole (:mod:`~.contact_forces`).
3. The system is statically indeterminate (two feet, four corners each), so among the admissible
   forces we take the ones a torque-minimising controller would use: minimise the squared hinge
   torques plus a small regularisation (tangential force costs ``TANGENTIAL_COST`` times more than
   normal force), the wrench equality a stiff penalty. A wrench no admissible force supplies
   (flight, ZMP outside the soles, not enough friction) leaves a residual, reported per frame. The
   torques are therefore close to the least any admissible contact distribution needs: a joint
   over its limit here is over it for every controller, and no figure rests on a force the floor
   cannot give.
4. Hinge torques are tau_h - J_h f with the hinge rows of the contact Jacobian. Optionally the
   servo's own reflected inertia and damping (the MJCF's armature * qacc + damping * qvel) are
   added: the damping of a servo model is its speed-torque slope, so this is the torque the motor
   must make.

The multi-body ZMP follows from the same root wrench: the floor point where the required moment
has no horizontal component. Where the forces supply the wrench (residual ~ 0) it equals their
centre of pressure ``cop_xy``; where they cannot, the ZMP says where the pressure would have to be.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2robot.robot.chains import foot_ancestor_mask
from motion2robot.robot.robot import Robot
from motion2robot.validate.contact_forces import (
    CORNERS,
    corner_map,
    foot_wrench_rows,
    friction_coefficients,
    solve_contact_forces,
)
from motion2robot.validate.kinematics import Kinematics
from motion2robot.validate.models import floor_geom

#: Cost of a tangential unit force relative to a normal one in the force regularisation.
TANGENTIAL_COST = 100.0
#: Weight of the force regularisation relative to the hinge torques, per squared robot height (m^2).
REGULARISATION = 1e-3
#: Weight of the root-wrench equality (penalty), per squared robot height (m^2).
PENALTY = 1e6
#: A frame whose required vertical force is below this fraction of m*g has no defined ZMP.
MIN_NORMAL_FRACTION = 0.05
#: Unsupplied force (fraction of m*g) or moment (fraction of m*g*height) above which a frame's
#: contact forces are not admissible (the penalty leaves ~0.1 % near the edge of what friction and
#: the soles allow: numerical, not a finding).
RESIDUAL_TOLERANCE = 1e-2


@dataclass(frozen=True, eq=False)
class Dynamics:
    """tau (T, n) hinge torques (N*m) in ``joint_names`` order, of which servo_tau (T, n) is the
    servo's own armature * qacc + damping * qvel (zero without servo dynamics); forces (T, 2, 4, 3)
    floor reaction per sole corner (N, world), each inside its friction cone; mu (2,) friction per
    foot; residual (T, 6) unsupplied root wrench [force; moment about the root] (world);
    supplied (T,) bool: the residual is within ``RESIDUAL_TOLERANCE``; zmp_xy (T, 2) multi-body
    ZMP of the required wrench (NaN where undefined); cop_xy (T, 2) centre of pressure of
    ``forces`` (NaN without load); normal_force (T,) total required vertical force (N); fallback
    (T,) bool frames the library QP solved."""

    tau: np.ndarray
    servo_tau: np.ndarray
    forces: np.ndarray
    mu: np.ndarray
    residual: np.ndarray
    supplied: np.ndarray
    zmp_xy: np.ndarray
    cop_xy: np.ndarray
    normal_force: np.ndarray
    fallback: np.ndarray

    @property
    def normal(self) -> np.ndarray:
        """(T, 2, 4) corner normal forces (N)."""
        return self.forces[..., 2]


def contact_rows(kin: Kinematics, robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A_w (T, 6, 12), J_w (T, n, 12), C (T, 12, 24)): root rows and hinge rows of the feet's
    wrenches, and the map from the corner forces [f_x, f_y, f_z per corner; left corners 0-3,
    right 0-3] to those wrenches (see :mod:`~motion2robot.validate.contact_forces`)."""
    centres = kin.corners.mean(axis=2)
    A, J = foot_wrench_rows(centres, kin.qpos[:, :3], kin.xaxis, kin.xanchor, foot_ancestor_mask(robot))
    return A, J, corner_map(kin.corners, centres)


def centre_of_pressure(forces: np.ndarray, corners: np.ndarray, min_force: float) -> np.ndarray:
    """(T, 2) floor point of the normal forces (T, 2, 4, 3) at ``corners`` (T, 2, 4, 3); NaN below
    ``min_force`` N in all."""
    fz = forces[..., 2].reshape(len(forces), -1)
    total = fz.sum(axis=1)
    ok = total > min_force
    cop = (fz[..., None] * corners[..., :2].reshape(len(forces), -1, 2)).sum(axis=1) / np.where(ok, total, 1.0)[:, None]
    cop[~ok] = np.nan
    return cop


def root_wrench(kin: Kinematics) -> np.ndarray:
    """(T, 6) the wrench the world must supply at the root: force (N) and moment about the root
    origin (N*m), world axes (the free joint's rows of ``mj_rne``)."""
    moment_root = (kin.root_xmat @ kin.rne[:, 3:6, None])[..., 0]
    return np.concatenate([kin.rne[:, :3], moment_root], axis=1)


def zmp_of_wrench(root_pos: np.ndarray, wrench: np.ndarray, min_force: float) -> np.ndarray:
    """(T, 2) multi-body ZMP: the floor point (z = 0) where the required wrench (T, 6) about the
    root origins (T, 3) has no horizontal moment; NaN where its vertical force is below
    ``min_force`` N."""
    N0 = np.cross(root_pos, wrench[:, :3]) + wrench[:, 3:]  # moment about the world origin
    Fz = wrench[:, 2]
    ok = Fz > min_force
    safe = np.where(ok, Fz, 1.0)
    zmp = np.stack([-N0[:, 1] / safe, N0[:, 0] / safe], axis=1)
    zmp[~ok] = np.nan
    return zmp


def inverse_dynamics(kin: Kinematics, robot: Robot, support: np.ndarray, *,
                     servo_dynamics: bool = True) -> Dynamics:
    """Hinge torques and admissible contact forces for the trajectory in ``kin``.

    support: (T, 2, 4) bool sole corners that may push on the floor."""
    T = kin.num_frames
    root_pos = kin.qpos[:, :3]
    wrench = root_wrench(kin)
    bias = kin.rne[:, 6:]
    A, J, C = contact_rows(kin, robot)
    mu = friction_coefficients(kin.model, robot.foot_bodies, floor_geom(kin.model))
    h2 = max(robot.height, 1e-3) ** 2
    reg = REGULARISATION * h2 * np.tile([TANGENTIAL_COST, TANGENTIAL_COST, 1.0], 2 * CORNERS)
    pen = PENALTY * h2
    Jt, At = J.transpose(0, 2, 1), A.transpose(0, 2, 1)
    Q = Jt @ J + pen * (At @ A)
    q = (Jt @ bias[..., None] + pen * (At @ wrench[..., None]))[..., 0]
    f, _, fallback = solve_contact_forces(Q, q, C, reg, support.reshape(T, 2 * CORNERS), mu)
    feet = (C @ f.reshape(T, -1, 1))  # (T, 12, 1) the feet's wrenches
    tau = bias - (J @ feet)[..., 0]
    residual = wrench - (A @ feet)[..., 0]
    weight = robot.mass * 9.81
    supplied = ((np.linalg.norm(residual[:, :3], axis=1) <= RESIDUAL_TOLERANCE * weight)
                & (np.linalg.norm(residual[:, 3:], axis=1) <= RESIDUAL_TOLERANCE * weight * robot.height))
    servo = np.zeros_like(tau)
    if servo_dynamics:
        m = robot.model
        dofs = m.jnt_dofadr[np.asarray(robot.joint_ids)]
        servo = m.dof_armature[dofs] * kin.qacc[:, 6:] + m.dof_damping[dofs] * kin.qvel[:, 6:]
        tau = tau + servo
    zmp = zmp_of_wrench(root_pos, wrench, MIN_NORMAL_FRACTION * weight)
    Fz = wrench[:, 2]
    forces = f.reshape(T, 2, CORNERS, 3)
    cop = centre_of_pressure(forces, kin.corners, MIN_NORMAL_FRACTION * weight)
    return Dynamics(tau=tau, servo_tau=servo, forces=forces, mu=mu, residual=residual, supplied=supplied,
                    zmp_xy=zmp, cop_xy=cop, normal_force=Fz, fallback=fallback)

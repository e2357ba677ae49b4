"""Inverse dynamics with the floor reaction: contact Jacobian rows, ZMP, finite differences."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate import examples
from motion2robot.validate.context import prepare
from motion2robot.validate.dynamics import contact_rows
from motion2robot.validate.kinematics import differentiate
from motion2robot.validate.options import CheckOptions


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def yawed_waving(robot, yaw=0.7):
    """Waving with the whole robot turned about z (exercises the root frame conversions)."""
    m = examples.waving(robot)
    q = m.qpos.copy()
    c, s = np.cos(yaw), np.sin(yaw)
    q[:, :2] = q[:, :2] @ np.array([[c, s], [-s, c]])
    q[:, 3:7] = np.array([np.cos(yaw / 2), 0, 0, np.sin(yaw / 2)])
    return RobotMotion(q, m.fps, m.joint_names, m.robot)


def test_differentiate_matches_mujoco(op3):
    mo = yawed_waving(op3)
    q = mo.qpos.copy()
    t = np.arange(len(q)) / mo.fps
    ang = 0.7 + 0.3 * np.sin(2 * t)
    q[:, 3:7] = np.stack([np.cos(ang / 2), 0 * ang, np.sin(0.1) * np.sin(ang / 2), np.cos(0.1) * np.sin(ang / 2)], axis=1)
    q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1, keepdims=True)
    qvel, qacc = differentiate(q, mo.fps)
    for k in (5, 60, 120):
        ref = np.zeros(op3.model.nv)
        mujoco.mj_differentiatePos(op3.model, ref, 2.0 / mo.fps, q[k - 1], q[k + 1])
        np.testing.assert_allclose(qvel[k], ref, atol=2e-3)
    assert qacc.shape == qvel.shape


def test_contact_rows_are_the_jacobian_transpose(op3):
    """A^T and J^T of the 24 corner-force unknowns equal MuJoCo's site Jacobians at a frame."""
    ctx = prepare(yawed_waving(op3), op3, CheckOptions())
    A, J, C = contact_rows(ctx.kin, op3)
    A, J = A @ C, J @ C  # corner forces -> root and hinge rows
    t = 70
    m, d = op3.model, mujoco.MjData(op3.model)
    d.qpos[:] = ctx.kin.qpos[t]
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    f = np.random.default_rng(0).normal(size=24)
    gen = np.zeros(m.nv)
    for k in range(2):
        for c in range(4):
            jp = np.zeros((3, m.nv))
            mujoco.mj_jacSite(m, d, jp, None, int(op3.sole_sites[k, c]))
            gen += jp.T @ f[3 * (4 * k + c): 3 * (4 * k + c) + 3]
    R = d.xmat[op3.root_body].reshape(3, 3)
    root_rows = np.concatenate([gen[:3], R @ gen[3:6]])  # MuJoCo's free rotation rows are local
    np.testing.assert_allclose(A[t] @ f, root_rows, atol=1e-9)
    np.testing.assert_allclose(J[t] @ f, gen[6:], atol=1e-9)


def test_standing_still_is_supported_with_zmp_at_the_com(op3):
    ctx = prepare(examples.standing(op3), op3, CheckOptions(servo_dynamics=False))
    dyn = ctx.dyn
    np.testing.assert_allclose(dyn.zmp_xy, ctx.kin.com[:, :2], atol=1e-9)
    assert np.abs(dyn.residual).max() < 1e-3
    assert dyn.normal.sum(axis=(1, 2)) == pytest.approx(np.full(len(dyn.tau), op3.mass * 9.81), rel=1e-4)
    assert (dyn.normal >= 0).all()
    # symmetric stance: mirrored knees carry mirrored torques
    lk, rk = op3.joint_index("l_knee"), op3.joint_index("r_knee")
    assert dyn.tau[0, lk] == pytest.approx(-dyn.tau[0, rk], rel=0.05)


def test_flight_leaves_the_weight_as_residual(op3):
    q = examples.standing(op3).qpos.copy()
    q[:, 2] += 0.05  # both feet 5 cm in the air
    ctx = prepare(RobotMotion(q, 50, op3.joint_names, "op3"), op3, CheckOptions())
    assert not ctx.support.any()
    assert ctx.dyn.residual[:, 2] == pytest.approx(np.full(len(q), op3.mass * 9.81), rel=1e-6)
    assert np.abs(ctx.dyn.normal).max() == 0.0


def test_servo_dynamics_adds_damping_torque(op3):
    mo = examples.waving(op3)
    with_servo = prepare(mo, op3, CheckOptions(servo_dynamics=True)).dyn.tau
    rigid = prepare(mo, op3, CheckOptions(servo_dynamics=False)).dyn.tau
    j = op3.joint_index("l_el")
    qvel = prepare(mo, op3, CheckOptions()).kin.qvel[:, 6 + j]
    dof = 6 + j
    expected = op3.model.dof_damping[dof] * qvel
    np.testing.assert_allclose((with_servo - rigid)[:, j], expected + op3.model.dof_armature[dof]
                               * prepare(mo, op3, CheckOptions()).kin.qacc[:, dof], atol=1e-9)

"""The casadi forward kinematics built from the MuJoCo tree agrees with MuJoCo's own."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from motion2robot.robot import load_robot
from motion2robot.robot.kinematics import fk_function
from tests._shared import requires_menagerie


def _compare(robot, n=5, seed=0):
    m = robot.model
    fk = fk_function(m, robot.root_body)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(seed)
    worst = 0.0
    for _ in range(n):
        q = robot.nominal_qpos.copy()
        q[:3] = rng.normal(size=3)
        quat = rng.normal(size=4)
        q[3:7] = quat / np.linalg.norm(quat)
        q[7:] = rng.uniform(robot.lower, robot.upper)
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        xpos, xmat, sites, com = (np.asarray(a) for a in fk(q))
        worst = max(worst, abs(xpos.T - d.xpos).max(), abs(xmat.T - d.xmat).max(),
                    abs(sites.T - d.site_xpos).max(), abs(com.ravel() - d.subtree_com[robot.root_body]).max())
    return worst


def test_fk_matches_mujoco_op3():
    assert _compare(load_robot("op3")) < 1e-9


@requires_menagerie
@pytest.mark.parametrize("name", ["menagerie:unitree_g1", "menagerie:unitree_h1"])
def test_fk_matches_mujoco_menagerie(name, monkeypatch):
    from tests._shared import MENAGERIE
    monkeypatch.setenv("MENAGERIE_ROOT", str(MENAGERIE))
    assert _compare(load_robot(name), n=3) < 1e-9


def test_fk_detects_a_wrong_tree():
    """The comparison can fail: a model whose body offset changed gives a different FK."""
    robot = load_robot("op3")
    fk = fk_function(robot.model, robot.root_body)
    spec = mujoco.MjSpec.from_file(robot.mjcf_path)
    body = next(b for b in spec.bodies if b.name and b.name != "world" and b.parent.name != "world")
    body.pos = [body.pos[0] + 0.01, body.pos[1], body.pos[2]]
    other = spec.compile()
    d = mujoco.MjData(other)
    d.qpos[:] = robot.nominal_qpos[: other.nq]
    mujoco.mj_kinematics(other, d)
    xpos = np.asarray(fk(robot.nominal_qpos)[0]).T
    assert abs(xpos[: other.nbody] - d.xpos).max() > 1e-3


def test_tangent_jacobians_match_finite_differences():
    """The problem's geometric (first-order) points have the exact Jacobian of the exact points:
    keypoints, sole corners, CoM and capsule clearances, against central differences of the
    tangent step (root translation, root-local rotation vector, hinges)."""
    import casadi as ca

    from motion2robot.retarget import problem as P

    robot = load_robot("op3")
    spec = P.build_spec(robot)
    q, dx = ca.SX.sym("q", robot.nq), ca.SX.sym("dx", spec.nv)
    _, kp, corners, com, gaps = P._geometry(spec, q, dx)
    pts = ca.vertcat(*kp, *corners, com, *gaps)
    f = ca.Function("f", [q, dx], [pts, ca.jacobian(pts, dx)])
    rng = np.random.default_rng(3)
    q0 = robot.nominal_qpos.copy()
    q0[7:] = 0.5 * rng.uniform(robot.lower, robot.upper)
    quat = rng.normal(size=4)
    q0[3:7] = quat / np.linalg.norm(quat)
    zero = np.zeros(spec.nv)
    J = np.asarray(f(q0, zero)[1])
    h = 1e-6
    for i in range(spec.nv):
        d = np.zeros((1, spec.nv))
        d[0, i] = h
        plus = np.asarray(f(P.apply_step(q0[None], d)[0], zero)[0]).ravel()
        minus = np.asarray(f(P.apply_step(q0[None], -d)[0], zero)[0]).ravel()
        assert np.abs(J[:, i] - (plus - minus) / (2 * h)).max() < 1e-7

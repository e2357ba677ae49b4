"""Contact forces the floor could really supply: the friction cone, the soles, the solver, and
torques that agree with independent computations."""

from __future__ import annotations

import dataclasses
import sys

import casadi as ca
import mujoco
import numpy as np
import pytest

from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate import check, examples
from motion2robot.validate.balance import balance
from motion2robot.validate.contact_forces import inside_cone, solve_nonnegative
from motion2robot.validate.context import prepare
from motion2robot.validate.dynamics import inverse_dynamics
from motion2robot.validate.models import physics_model
from motion2robot.validate.options import CheckOptions
from tests._shared import load_menagerie, requires_menagerie


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def _random_qp(rng, T=60, m=32, free_share=0.8):
    M = rng.normal(size=(T, m + 6, m))
    H = M.transpose(0, 2, 1) @ M + 1e-3 * np.eye(m)
    H[: T // 2] *= np.logspace(0, 6, m)[None, :, None] ** 0.5 * np.logspace(0, 6, m)[None, None, :] ** 0.5  # badly scaled
    g = rng.normal(size=(T, m)) * 10
    free = rng.random((T, m)) < free_share
    return H, g, free


def _library(H, g, free):
    m = g.shape[1]
    s = ca.conic("ref", "qpoases", {"h": ca.Sparsity.dense(m, m), "a": ca.Sparsity(0, m)}, {"printLevel": "none"})
    out = []
    for t in range(len(g)):
        r = s(h=H[t], g=-g[t], lbx=np.zeros(m), ubx=np.where(free[t], np.inf, 0.0))
        out.append(np.asarray(r["x"]).ravel())
    return np.array(out)


def test_batched_solver_matches_a_library_qp():
    rng = np.random.default_rng(3)
    H, g, free = _random_qp(rng)
    x, fallback = solve_nonnegative(H, g, free)
    ref = _library(H, g, free)
    assert (x >= 0).all() and (x[~free] == 0).all()
    obj = lambda v: 0.5 * np.einsum("ti,tij,tj->t", v, H, v) - np.einsum("ti,ti->t", g, v)  # noqa: E731
    np.testing.assert_allclose(obj(x), obj(ref), rtol=1e-7, atol=1e-9)
    assert not fallback.any()


def test_cycling_frames_are_finished_by_lawson_hanson(monkeypatch):
    """With no primal-dual passes at all every frame goes through Lawson-Hanson: same optimum."""
    import motion2robot.validate.contact_forces as cf
    rng = np.random.default_rng(4)
    H, g, free = _random_qp(rng, T=30)
    ref, _ = solve_nonnegative(H, g, free)
    monkeypatch.setattr(cf, "PDAS_ITERATIONS", 0)
    x, fallback = cf.solve_nonnegative(H, g, free)
    np.testing.assert_allclose(x, ref, rtol=1e-6, atol=1e-8)
    assert not fallback.any()


def _spinning(robot, fps=100.0, amplitude=0.5, hz=4.0):
    """Standing, the whole robot yawing back and forth about its root fast, soles labelled down."""
    q = examples.standing(robot, seconds=1.0, fps=fps).qpos.copy()
    yaw = amplitude * np.sin(2 * np.pi * hz * np.arange(len(q)) / fps)
    q[:, 3:7] = np.stack([np.cos(yaw / 2), 0 * yaw, 0 * yaw, np.sin(yaw / 2)], axis=1)
    return RobotMotion(q, fps, robot.joint_names, robot.name, meta={"contacts": np.ones((len(q), 2), bool).tolist()})


def test_forces_stay_in_the_cone_and_the_cop_on_the_soles(op3):
    for motion in (examples.waving(op3), examples.slow_lean(op3), _spinning(op3)):
        ctx = prepare(motion, op3, CheckOptions())
        dyn = ctx.dyn
        f = dyn.forces.reshape(len(f_ := dyn.forces), 8, 3)
        # inside the true (circular) cone, unilateral, zero on corners that do not support
        assert (f[..., 2] >= -1e-9).all()
        mu = np.repeat(dyn.mu, 4)[None, :]
        assert (np.linalg.norm(f[..., :2], axis=-1) <= mu * f[..., 2] + 1e-9).all()
        assert inside_cone(f, dyn.mu, 1e-9).all()
        assert (f_.reshape(-1, 8, 3)[~ctx.support.reshape(-1, 8)] == 0).all()
        # where the forces supply the wrench their centre of pressure is the ZMP
        w = op3.mass * 9.81
        exact = (np.linalg.norm(dyn.residual[:, :3], axis=1) < 1e-3 * w) & (np.linalg.norm(dyn.residual[:, 3:], axis=1) < 1e-4 * w)
        ok = exact & np.isfinite(dyn.zmp_xy).all(axis=1)
        assert ok.any()
        np.testing.assert_allclose(dyn.cop_xy[ok], dyn.zmp_xy[ok], atol=2e-3)


def _settled(robot, seconds=3.0):
    """MuJoCo's own answer: the robot dropped on the floor holding its nominal posture with the
    servo model until it is still; returns (qpos, actuator torques)."""
    m = physics_model(robot)
    d = mujoco.MjData(m)
    q0 = robot.nominal_qpos
    d.qpos[:] = q0
    d.ctrl[:] = q0[7:]
    for _ in range(int(seconds / m.opt.timestep)):
        mujoco.mj_step(m, d)
    assert np.abs(d.qvel).max() < 1e-3
    return d.qpos.copy(), d.qfrc_actuator[6:].copy()


def _gravity_torques_both_feet_loaded(robot, name):
    q, tau_sim = _settled(robot)
    motion = RobotMotion(np.tile(q, (10, 1)), 50.0, robot.joint_names, name)
    ctx = prepare(motion, robot, CheckOptions(servo_dynamics=False))
    assert ctx.support.all() and ctx.dyn.supplied.all()
    ratio = np.abs(ctx.dyn.tau[5] - tau_sim) / np.asarray(robot.torque_limit)
    return ratio, ctx


def test_standing_torques_match_mujocos_physics_op3(op3):
    """Standing still: every joint's torque within 5 % of its limit of what MuJoCo's contact
    solver needs to hold the settled posture (an independent distribution of the weight)."""
    ratio, ctx = _gravity_torques_both_feet_loaded(op3, "op3")
    assert ratio.max() < 0.05
    # both feet loaded, about equally
    per_foot = ctx.dyn.normal[5].sum(axis=1)
    assert per_foot.min() > 0.4 * op3.mass * 9.81


@requires_menagerie
def test_standing_torques_match_mujocos_physics_g1():
    g1 = load_menagerie("menagerie:unitree_g1")
    ratio, _ = _gravity_torques_both_feet_loaded(g1, g1.name)
    assert ratio.max() < 0.05


def _independent_torques(robot, ctx, t: int) -> np.ndarray:
    """Hinge torques of frame t from an independent solve: IPOPT over the 8 corner forces with
    MuJoCo's site Jacobians, circular friction cones and the root wrench supplied exactly, the same
    objective (squared hinge torques plus the force regularisation) as the check's."""
    m, d = robot.model, mujoco.MjData(robot.model)
    d.qpos[:], d.qvel[:] = ctx.kin.qpos[t], ctx.kin.qvel[t]
    mujoco.mj_forward(m, d)
    d.qacc[:] = ctx.kin.qacc[t]  # mj_forward wrote its own
    rne = np.zeros(m.nv)
    mujoco.mj_rne(m, d, 1, rne)
    jac = []
    for k in range(2):
        for c in range(4):
            jp = np.zeros((3, m.nv))
            mujoco.mj_jacSite(m, d, jp, None, int(robot.sole_sites[k, c]))
            jac.append(jp)
    Jc = np.concatenate(jac, axis=0)  # (24, nv)
    f = ca.MX.sym("f", 24)
    gen = ca.mtimes(Jc.T, f)
    tau = rne[6:] - gen[6:]
    mu = float(ctx.dyn.mu[0])
    cons = [rne[:6] - gen[:6]]  # the root wrench supplied exactly
    cons += [mu * f[3 * c + 2] - ca.sqrt(f[3 * c] ** 2 + f[3 * c + 1] ** 2 + 1e-12) for c in range(8)]
    h2 = robot.height ** 2
    reg = 1e-3 * h2 * ca.sumsqr(ca.vertcat(*[ca.vertcat(10 * f[3 * c], 10 * f[3 * c + 1], f[3 * c + 2]) for c in range(8)]))
    nlp = {"x": f, "f": ca.sumsqr(tau) + reg, "g": ca.vertcat(*cons)}
    solver = ca.nlpsol("ref", "ipopt", nlp, {"ipopt.print_level": 0, "print_time": False, "ipopt.tol": 1e-12})
    x0 = np.tile([0.0, 0.0, robot.mass * 9.81 / 8], 8)
    sol = solver(x0=x0, lbg=np.r_[np.zeros(6), np.zeros(8)], ubg=np.r_[np.zeros(6), np.full(8, np.inf)])
    return np.asarray(ca.Function("t", [f], [tau])(sol["x"])).ravel()


def test_same_optimum_as_an_independent_solve_with_exact_cones(op3):
    """The torque-minimising admissible forces of a waving frame and of standing still give the same
    torques as the independent IPOPT solve."""
    for motion, t in ((examples.waving(op3), 100), (examples.standing(op3), 10)):
        ctx = prepare(motion, op3, CheckOptions(servo_dynamics=False))
        ref = _independent_torques(op3, ctx, t)
        assert np.abs(ctx.dyn.tau[t] - ref).max() <= 0.05 * np.abs(ref).max()


@requires_menagerie
@pytest.mark.parametrize("name", ["pal_talos", "unitree_g1"])
def test_standing_torques_of_big_humanoids_match_the_independent_solve(name, tmp_path, monkeypatch):
    """Standing still at the nominal pose (both feet loaded): within 5 % of the largest torque of
    the independent solve, on a shipped config (G1) and on a drafted one (Talos, which tips over in
    the position-servo playback, so MuJoCo's settled posture is not available)."""
    from tests._shared import MENAGERIE
    monkeypatch.setenv("MENAGERIE_ROOT", str(MENAGERIE))
    if name == "unitree_g1":
        robot = load_menagerie("menagerie:unitree_g1")
    else:
        from motion2robot.robot.draft import draft_config, write_draft
        robot = load_robot(str(write_draft(draft_config(f"menagerie:{name}", name=f"{name}_draft"),
                                           tmp_path / f"{name}.toml")))
    motion = RobotMotion(np.tile(robot.nominal_qpos, (20, 1)), 50.0, robot.joint_names, robot.name)
    ctx = prepare(motion, robot, CheckOptions(servo_dynamics=False))
    assert ctx.support.all() and ctx.dyn.supplied.all()
    ref = _independent_torques(robot, ctx, 10)
    err = np.abs(ctx.dyn.tau[10] - ref)
    assert err.max() <= 0.05 * np.abs(ref).max(), (err.max(), np.abs(ref).max())
    assert np.abs(ctx.dyn.tau[10]).max() < 2 * np.asarray(robot.torque_limit).max()


def test_feet_at_different_heights_do_not_make_a_lever_of_friction(op3):
    """The T1-like case: double support with one sole 8 mm higher while the body leans past its
    toes. Unlimited friction let opposing tangential forces on the two feet use the height
    difference as a lever (op3: 59 N*m, 14x the servo, 280 N sideways on a 31 N robot); with the
    cone the torques stay within what the leaning body needs and the feet push within friction."""
    ctx = prepare(examples.slow_lean(op3), op3, CheckOptions(servo_dynamics=False))
    support = np.ones_like(ctx.support)
    flat = inverse_dynamics(ctx.kin, op3, support, servo_dynamics=False)
    corners = ctx.kin.corners.copy()
    corners[:, 1, :, 2] += 0.008
    raised = inverse_dynamics(dataclasses.replace(ctx.kin, corners=corners), op3, support, servo_dynamics=False)
    weight = op3.mass * 9.81
    assert np.abs(raised.forces[..., :2]).sum(axis=(1, 2)).max() <= np.abs(raised.forces[..., 2]).sum(axis=(1, 2)).max() * raised.mu.max() + 1e-9
    assert raised.forces[..., 2].sum(axis=(1, 2)).max() < 1.5 * weight
    assert np.abs(raised.tau).max() < 2.5 * np.abs(flat.tau).max()
    assert np.abs(raised.tau).max() < np.asarray(op3.torque_limit).max()


def test_spinning_on_flat_soles_is_reported_as_slipping(op3):
    """Yawing the whole body fast on planted soles needs more twist than friction gives: the ZMP
    stays under the body, but the check says the feet would spin."""
    motion = _spinning(op3)
    ctx = prepare(motion, op3, CheckOptions())
    assert ctx.support.all()
    b = balance(ctx)
    assert not b["ok"] and b["slip_frames"] and not b["zmp_outside_frames"]
    assert b["slip_worst"]["twist_nm"] > 0.1
    report = check(motion, op3, CheckOptions(physics=False))
    assert any("no friction-feasible contact forces" in r for r in report.reasons)
    # the same body turning slowly is fine
    slow = _spinning(op3, hz=0.25, amplitude=0.3)
    assert balance(prepare(slow, op3, CheckOptions()))["slip_frames"] == []


if __name__ == "__main__":  # pragma: no cover
    sys.exit(pytest.main([__file__, "-q"]))

"""Smoothness of the retargeted trajectories: the smoothing maths (pentadiagonal solve, C kernels
= numpy), the solver's temporal diagonal, and no frame-to-frame zigzag on the demo and real
quasi-static clips, whose acceleration (and, for the demo, every) check passes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2robot.motion import read_motion
from motion2robot.retarget import RetargetOptions, Weights, native, whole_body as retarget
from motion2robot.retarget.constraints import clamp_velocity
from motion2robot.retarget.metrics import peak_acceleration, velocity_reversals
from motion2robot.retarget.smoothing import _smooth, servo_targets, smooth_hinges, smooth_to_targets
from motion2robot.retarget.solver import _temporal
from motion2robot.robot import load_robot
from motion2robot.validate import CheckOptions, check
from tests._shared import MOTIONS, requires_shared

DEMO = Path(__file__).resolve().parents[1] / "motion2robot" / "data" / "demo_wave_squat.npy"


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


@pytest.fixture
def numpy_only(monkeypatch):
    """The numpy fallbacks instead of the compiled kernels."""
    monkeypatch.setenv("MOTION2ROBOT_NATIVE", "0")
    native.library.cache_clear()
    yield
    native.library.cache_clear()


def _dense(r: np.ndarray, u: np.ndarray, m: np.ndarray) -> np.ndarray:
    T = len(r)
    out = np.empty_like(r)
    for j in range(r.shape[1]):
        A = np.eye(T)
        for t in range(T - 1):
            d = np.zeros(T)
            d[t], d[t + 1] = -1.0, 1.0
            A += u[t, j] * np.outer(d, d)
        for t in range(T - 2):
            d = np.zeros(T)
            d[t:t + 3] = 1.0, -2.0, 1.0
            A += m[t, j] * np.outer(d, d)
        out[:, j] = np.linalg.solve(A, r[:, j])
    return out


def _problem(seed: int = 0, T: int = 40, k: int = 3):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(T, k)), rng.uniform(0, 5, (T - 1, k)), rng.uniform(0, 5, (T - 2, k))


def test_pentadiagonal_solve_matches_dense():
    r, u, m = _problem()
    np.testing.assert_allclose(_smooth(r, u, m), _dense(r, u, m), atol=1e-10)


def test_pentadiagonal_solve_numpy_fallback(numpy_only):
    assert native.library() is None
    r, u, m = _problem(1)
    np.testing.assert_allclose(_smooth(r, u, m), _dense(r, u, m), atol=1e-10)


def test_velocity_clamp_same_in_c_and_numpy(monkeypatch):
    q = np.cumsum(np.random.default_rng(2).normal(size=(60, 5)), axis=0)
    step = np.array([0.2, 0.5, 1.0, 2.0, 0.05])
    fast = clamp_velocity(q, step, 1.0)
    monkeypatch.setenv("MOTION2ROBOT_NATIVE", "0")
    native.library.cache_clear()
    try:
        slow = clamp_velocity(q, step, 1.0)
    finally:
        native.library.cache_clear()
    np.testing.assert_allclose(fast, slow, atol=0)
    assert np.all(np.abs(np.diff(fast, axis=0)) <= step + 1e-12)


def test_reweighting_loop_same_in_c_and_numpy(monkeypatch):
    """The C reweighting loop (which re-solves only the columns whose weights changed) gives the
    numpy loop's answer; columns at different distances from their targets."""
    rng = np.random.default_rng(4)
    q = np.cumsum(rng.normal(0, 0.05, (150, 6)), axis=0) * np.array([1.0, 0.1, 2.0, 0.5, 0.02, 1.5])
    vt, at = np.array([2.0, 2.0, 3.0, 1.0, 2.0, 2.5]), np.array([30.0, 30.0, 10.0, 50.0, 30.0, 20.0])
    fast = smooth_to_targets(q, vt, at, 30.0)
    monkeypatch.setenv("MOTION2ROBOT_NATIVE", "0")
    native.library.cache_clear()
    try:
        slow = smooth_to_targets(q, vt, at, 30.0)
    finally:
        native.library.cache_clear()
    assert np.abs(fast - q).max() > 0.01                      # it did smooth something
    np.testing.assert_allclose(fast, slow, atol=1e-12)


def test_smoothing_rounds_off_a_bang_bang_and_keeps_calm_joints():
    fps = 20.0
    t = np.arange(80) / fps
    zigzag = 0.25 * (np.arange(80) % 2)                     # +-5 rad/s every frame
    calm = 0.2 * np.sin(2 * np.pi * 0.3 * t)                 # 0.38 rad/s, 0.7 rad/s^2
    q = np.stack([zigzag, calm], axis=1)
    out = smooth_to_targets(q, np.array([2.0, 2.0]), np.array([20.0, 20.0]), fps)
    assert np.abs(np.diff(out[:, 0])).max() * fps <= 2.0 + 1e-9
    assert np.abs(np.diff(out[:, 0], 2)).max() * fps ** 2 <= 20.0 + 1e-9
    assert velocity_reversals(out, fps) == 0
    np.testing.assert_array_equal(out[:, 1], calm)           # within the targets: untouched


def test_smooth_hinges_keeps_limits(op3):
    rng = np.random.default_rng(3)
    q = rng.uniform(op3.lower - 0.3, op3.upper + 0.3, size=(50, op3.n_joints))
    out = smooth_hinges(q, *servo_targets(op3), 20.0, op3.velocity_limit, op3.lower, op3.upper)
    assert np.all(out >= op3.lower) and np.all(out <= op3.upper)
    assert np.all(np.abs(np.diff(out, axis=0)) * 20.0 <= op3.velocity_limit + 1e-9)


def test_servo_targets_leave_torque_for_the_load(op3):
    v, a = servo_targets(op3)
    m = op3.model
    dof = m.jnt_dofadr[np.asarray(op3.joint_ids)]
    servo = m.dof_damping[dof] * v + m.dof_armature[dof] * a
    assert np.all(v <= op3.velocity_limit) and np.all(servo < 0.9 * np.asarray(op3.torque_limit))


def test_temporal_diagonal_majorises_the_temporal_hessian():
    """diag - Hessian of the velocity + acceleration terms is positive semi-definite, so the
    simultaneous (block-Jacobi) update of all frames cannot amplify the odd/even mode."""
    T, nv = 12, 8
    w = Weights(velocity=0.7, acceleration=1.3)
    Q = np.zeros((T, nv + 1))
    Q[:, 3] = 1.0  # identity root quaternion (nq = nv + 1)
    _, diag, _ = _temporal(Q, np.ones(nv), w)
    D1 = np.diff(np.eye(T), axis=0)
    D2 = np.diff(np.eye(T), 2, axis=0)
    H = w.velocity * D1.T @ D1 + w.acceleration * D2.T @ D2  # per coordinate, in the solver's J'J convention
    assert np.linalg.eigvalsh(np.diag(diag[:, 0]) - H).min() >= -1e-12
    # the previous diagonal (1 per velocity neighbour, 1-4-1 per acceleration row) does not
    plain = w.velocity * (np.abs(D1).T @ np.ones(T - 1)) + w.acceleration * (D2 ** 2).T @ np.ones(T - 2)
    assert np.linalg.eigvalsh(np.diag(plain) - H).min() < -0.1


@requires_shared
@pytest.mark.parametrize("path", [str(DEMO), "bvh/bandai_byebye_normal_001.bvh", "humanml3d_joints/M010968.npy"])
def test_quasi_static_clips_are_smooth(op3, path):
    human = read_motion(DEMO if path == str(DEMO) else MOTIONS / path)[0]
    motion = retarget(human, op3)
    hinge = motion.qpos[:, 7:]
    assert velocity_reversals(hinge, motion.fps) == 0
    report = check(motion, op3, CheckOptions(physics=False))
    assert report.checks["acceleration"]["ok"], report.reasons
    assert report.checks["velocity_limits"]["ok"] and report.checks["joint_limits"]["ok"]
    assert peak_acceleration(hinge, motion.fps) < 91.0


def test_demo_is_feasible_with_physics(op3):
    """Every check passes on the demo, ``ground`` included: its planted soles hold at every corner."""
    motion = retarget(read_motion(DEMO)[0], op3)
    report = check(motion, op3)
    assert report.feasible, report.reasons
    g = report.checks["ground"]
    assert g["penetrations"] == [] and g["skimming"] == [] and g["slipping"] == []


@requires_shared
def test_smoothing_can_be_turned_off(op3):
    human = read_motion(MOTIONS / "humanml3d_joints" / "M010968.npy")[0]
    raw = retarget(human, op3, RetargetOptions(smoothing=False))
    smooth = retarget(human, op3)
    assert raw.meta["solver"]["smoothing"] is None
    assert smooth.meta["solver"]["smoothing"]["speed_target_rad_s"] == servo_targets(op3)[0].tolist()
    for m in (raw, smooth):
        assert np.all(np.abs(np.diff(m.qpos[:, 7:], axis=0)) * m.fps <= op3.velocity_limit + 1e-9)
    # the servo-aware smoothing is what keeps this arm raise within the rotor-inertia limit
    assert peak_acceleration(smooth.qpos[:, 7:], smooth.fps) < peak_acceleration(raw.qpos[:, 7:], raw.fps)


def test_native_root_steps_match_numpy():
    """apply_step / tangent_diff in C give numpy's numbers (the small-angle branch included)."""
    from motion2robot.retarget import native
    from motion2robot.retarget.problem import apply_step, tangent_diff

    if native.library() is None:
        pytest.skip("no C compiler")
    rng = np.random.default_rng(3)
    T, nq = 40, 27
    a, b = rng.normal(size=(T, nq)), rng.normal(size=(T, nq))
    for q in (a, b):
        q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1, keepdims=True)
    b[::3, 3:7] = a[::3, 3:7]
    dx = rng.normal(size=(T, nq - 1)) * 0.3
    dx[::4, 3:6] = 0.0
    fast = (apply_step(a, dx), tangent_diff(a, b))
    lib = native.library
    native.library = lambda: None
    try:
        slow = (apply_step(a, dx), tangent_diff(a, b))
    finally:
        native.library = lib
    assert np.array_equal(fast[0], slow[0])
    assert np.allclose(fast[1], slow[1], rtol=0, atol=1e-14)
    assert np.allclose(np.linalg.norm(fast[0][:, 3:7], axis=1), 1.0)


def test_low_pass_is_the_same_filter_at_any_frame_rate():
    """Motion at 2 Hz passes (within 1 % of its amplitude) at 20 and at 100 fps; 25 Hz solver noise
    at 100 fps loses 98 % of its amplitude (the discrete gain 1 / (1 + m (2 sin(pi f / fps))^4))."""
    from motion2robot.retarget.smoothing import low_pass

    for fps in (20.0, 100.0):
        t = np.arange(int(4 * fps)) / fps
        x = np.sin(2 * np.pi * 2.0 * t)[:, None]
        y = low_pass(x, fps)
        mid = slice(len(t) // 4, 3 * len(t) // 4)          # away from the ends
        assert np.abs(y[mid] - x[mid]).max() < 0.01
    t = np.arange(400) / 100.0
    noise = np.sin(2 * np.pi * 25.0 * t)[:, None]
    assert np.abs(low_pass(noise, 100.0)[100:300]).max() < 0.02


def test_low_pass_within_bounds_meets_them_without_a_kink():
    """A joint pressed against its limit: the filter rounds it past the limit; clipped afterwards,
    that is a kink whose acceleration grows with the rate (x2 at 200 fps). Within the bounds, the
    filter stays within them and its peak acceleration is the unbounded filter's."""
    from motion2robot.retarget.smoothing import low_pass

    fps = 200.0
    t = np.arange(int(2 * fps)) / fps
    x = np.minimum(1.0, 0.9 + 0.2 * np.sin(2 * np.pi * t))[:, None]

    def peak(y):
        return np.abs(np.diff(y[:, 0], 2)).max() * fps ** 2

    free = low_pass(x, fps)
    bounded = low_pass(x, fps, lower=np.array([-5.0]), upper=np.array([1.0]))
    assert free.max() > 1.001 and bounded.max() <= 1.0
    assert peak(np.clip(free, -5.0, 1.0)) > 1.5 * peak(free)
    assert peak(bounded) < 1.1 * peak(free)
    assert np.abs(bounded - x).max() < 0.02

"""Lane code (:mod:`motion2robot.retarget.lanes`): every generated function gives casadi's own
numbers, for every operation it supports, for any number of frames (a short last block
included), and the retargeting problem of op3 evaluated by it equals casadi's virtual machine."""

from __future__ import annotations

import ctypes

import casadi as ca
import numpy as np
import pytest

from motion2robot.retarget import lanes
from motion2robot.retarget.compiled import _compiler, _lane_library, compiled_problem
from motion2robot.retarget.costs import Weights
from motion2robot.robot import load_robot

pytestmark = pytest.mark.skipif(_compiler() is None, reason="needs a C compiler")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTION2ROBOT_CACHE", str(tmp_path))
    return tmp_path


def _casadi(f: ca.Function, inputs: list[np.ndarray], shared: tuple[int, ...]) -> list[np.ndarray]:
    T = next(len(x) for i, x in enumerate(inputs) if i not in shared)
    fm = f.map(T)
    args = [np.tile(np.reshape(x, (-1, 1)), (1, T)) if i in shared else np.asarray(x).T for i, x in enumerate(inputs)]
    return [np.array(o).T.reshape(T, -1) for o in fm(*args)] if f.n_out() > 1 else [np.array(fm(*args)).T.reshape(T, -1)]


def test_every_operation_matches_casadi(cache):
    x = ca.SX.sym("x", 3)
    s = ca.SX.sym("s", 2)
    a, b, c = x[0], x[1], x[2]
    outs = ca.vertcat(
        a + b, a - b, a * b, a / b, -a, ca.sqrt(ca.fabs(a)), a ** 2, 2 * a, ca.sin(a), ca.cos(b),
        a < b, a <= b, a == b, a != b, ca.logic_not(a < b), ca.logic_and(a < b, b < c), ca.logic_or(a < b, b < c),
        ca.if_else(a <= b, c, 0), ca.fmin(a, b), ca.fmax(a, c), ca.fmin(a, 0), ca.fmax(0, b),
        1 / b, ca.atan2(a, b), ca.exp(a), ca.log(ca.fabs(b) + 1), ca.tanh(c), ca.sign(a - b),
        s[0] * a + s[1], ca.sqrt(s[1]) * c,
    )
    f = ca.Function("m2r_test_ops", [x, s], [outs, a * s[0]], {"cse": True})
    lib, cached, _ = _lane_library({"ops": f}, shared={"ops": (1,)})
    ev = lanes.LaneEval(ctypes.CDLL(str(lib)), f, (1,))
    rng = np.random.default_rng(0)
    for T in (1, 3, 4, 7, 13):  # partial blocks of 2 or 4 lanes
        X = rng.normal(size=(T, 3))
        X[: T // 2, 1] = X[: T // 2, 0]                     # ties for ==, <=, fmin
        S = np.array([0.7, 2.0])
        got = ev(X, S)
        want = _casadi(f, [X, S], (1,))
        for g, w in zip(got, want):
            np.testing.assert_allclose(g, w, rtol=0, atol=1e-15)


def test_library_is_cached_by_source_and_flags(cache):
    x = ca.SX.sym("x")
    f = ca.Function("m2r_test_sq", [x], [x * x])
    first = _lane_library({"sq": f})
    again = _lane_library({"sq": f})
    assert first[0] == again[0] and not first[1] and again[1]
    g = ca.Function("m2r_test_sq", [x], [x * x + 1])
    assert _lane_library({"sq": g})[0] != first[0]


def test_unsupported_operation_falls_back():
    x = ca.SX.sym("x")
    f = ca.Function("m2r_test_erf", [x], [ca.erf(x)])
    with pytest.raises(NotImplementedError, match="erf|operation"):
        lanes.function_source(f)
    assert _lane_library({"erf": f}) is None


def test_op3_problem_same_as_casadi_virtual_machine():
    op3 = load_robot("op3")
    fast, vm = compiled_problem(op3), compiled_problem(op3, "vm")
    assert fast.backend == "lanes" and vm.backend == "vm"
    spec = fast.spec
    rng = np.random.default_rng(1)
    T, nv, n = 11, spec.nv, spec.n
    Q = np.tile(op3.nominal_qpos, (T, 1))
    Q[:, 7:] += rng.normal(0, 0.3, (T, n))
    Q[:, :3] += rng.normal(0, 0.05, (T, 3))
    P = np.abs(rng.normal(0, 0.1, (T, spec.n_params)))      # weights under square roots: >= 0
    w = np.array(Weights().frame_vector())
    lm = np.zeros((T, 1 + 2 * nv + 2 * n))
    lm[:, 0] = 1e-3
    lm[:, 1:1 + nv] = 0.1
    lm[:, 1 + 2 * nv:1 + 2 * nv + n] = op3.lower
    lm[:, 1 + 2 * nv + n:] = op3.upper
    calls = {"step": (Q, P, w, lm), "cost": (Q, P, w), "project": (Q, P, lm), "violation": (Q, P), "points": (Q,)}
    for name, args in calls.items():
        got, want = fast.evaluator(name, T)(*args), vm.evaluator(name, T)(*args)
        assert len(got) == len(want)
        for g, v in zip(got, want):
            assert g.shape == v.shape and np.all(np.isfinite(g))
            np.testing.assert_allclose(g, v, rtol=1e-12, atol=1e-12, err_msg=name)


def test_a_failing_compiler_falls_back_to_the_virtual_machine(cache, monkeypatch):
    monkeypatch.setenv("CC", "false")                                       # found on PATH, fails every compile
    problem = compiled_problem.__wrapped__(load_robot("op3"))
    assert problem.backend == "vm"
    T = 3
    kp = problem.points_eval(T)(np.tile(load_robot("op3").nominal_qpos, (T, 1)))[0]
    assert kp.shape[0] == T and np.all(np.isfinite(kp))

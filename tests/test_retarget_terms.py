"""The cost-term registry: every term declared once (name, weight, hard or soft, residual) and
everything else (term lists, weights, the compiled residual vector) derived from it."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np

from motion2robot.retarget.costs import FRAME_TERMS, HARD_TERMS, SOLVER_WEIGHTS, Weights
from motion2robot.retarget.terms import TERMS


def test_the_registry_defines_the_term_lists_and_the_weights():
    names = [t.name for t in TERMS]
    assert len(set(names)) == len(names) and tuple(names) == FRAME_TERMS
    assert set(HARD_TERMS) == {t.name for t in TERMS if t.hard} == {"contact_z", "contact_xy", "floor", "balance",
                                                                   "self_collision"}
    w = Weights()
    assert [f.name for f in dataclasses.fields(w)] == names + [n for n, _ in SOLVER_WEIGHTS]
    assert w.frame_vector() == [t.weight for t in TERMS]
    assert dataclasses.replace(w, keypoint=2.0).frame_vector()[0] == 2.0


def test_each_term_gives_its_rows_and_the_residual_vector_stacks_them_in_order():
    from motion2robot.retarget.problem import build_spec, residuals
    from motion2robot.robot import load_robot

    robot = load_robot("op3")
    spec = build_spec(robot)
    n_p = sum(s.stop - s.start for s in spec.layout.values())
    q, dx, p = ca.SX.sym("q", robot.model.nq), ca.SX.sym("dx", spec.nv), ca.SX.sym("p", n_p)
    w = ca.DM(Weights().frame_vector())
    r, costs, hard = residuals(spec, q, dx, p, w)
    f = ca.Function("f", [q, dx, p], [r, ca.vertcat(*costs)])
    rng = np.random.default_rng(1)
    args = [robot.nominal_qpos, 0.01 * rng.standard_normal(spec.nv), rng.standard_normal(n_p)]
    rv, cv = (np.asarray(x).ravel() for x in f(*args))
    # the vector is the weighted rows of each term in registry order; each term's cost its share
    at = 0
    for k, t in enumerate(TERMS):
        rows = ca.Function("g", [q, dx, p], [ca.vertcat(*_rows(spec, q, dx, p, t))])(*args)
        rows = np.asarray(rows).ravel()
        np.testing.assert_allclose(rv[at:at + rows.size], np.sqrt(t.weight) * rows, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(cv[k], t.weight * float(rows @ rows), rtol=1e-10, atol=1e-14)
        at += rows.size
    assert at == rv.size
    assert set(hard) == set(HARD_TERMS)


def _rows(spec, q, dx, p, term):
    from motion2robot.retarget.problem import _geometry
    from motion2robot.retarget.terms import Inputs

    tf, kp, corners, com, gaps = _geometry(spec, q, dx)
    rows = term.residual(Inputs(spec, {k: p[s] for k, s in spec.layout.items()}, tf, kp, corners, com, gaps, q, dx))
    return rows or [ca.SX.zeros(0, 1)]

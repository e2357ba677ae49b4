"""The Newton projection onto the hard constraints (solver.correct): exact where it can be,
never worse than its start where it cannot, always within the joint limits; the damped retry
gets a limb out of the torso where plain Newton steps zigzag."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.retarget.compiled import compiled_problem
from motion2robot.retarget.solver import correct
from motion2robot.retarget.targets import frame_params
from motion2robot.robot import load_robot


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def _params(problem, T, soles=None):
    labels = np.zeros((T, 2), dtype=bool) if soles is None else np.ones((T, 2), dtype=bool)
    return frame_params(problem.spec, np.zeros((T, 22, 3)), labels, soles, None, None)


def test_an_infeasible_pin_is_not_made_worse_and_keeps_the_limits(op3):
    problem = compiled_problem(op3)
    T = 6
    Q = np.tile(op3.nominal_qpos, (T, 1))
    corners = problem.points_eval(T)(Q)[1].reshape(T, 2, 4, 3)
    soles = corners.copy()
    soles[..., 2] = 0.0
    soles[:, 0, :, 0] += 0.6          # the left sole pinned 60 cm ahead of where it can reach
    soles[:, 1, :, 0] -= 0.6
    P = _params(problem, T, soles)
    v0 = problem.violation_eval(T)(Q, P)[0][:, 0]
    out, v = correct(problem, P, Q, op3.lower, op3.upper, None, 2, extra=8)
    assert np.all(np.isfinite(out)) and np.all(v <= v0 + 1e-15)
    assert np.all(out[:, 7:] >= op3.lower - 1e-12) and np.all(out[:, 7:] <= op3.upper + 1e-12)


def test_a_forearm_in_the_body_is_pushed_out(op3):
    problem = compiled_problem(op3)
    q = op3.nominal_qpos.copy()
    for name, value in (("l_sho_pitch", 0.0), ("l_sho_roll", 1.2), ("l_el", -1.2)):
        q[7 + op3.joint_names.index(name)] = value
    Q = q[None]
    assert problem.points_eval(1)(Q)[3].min() < -0.02                      # 2 cm and more inside
    out, v = correct(problem, _params(problem, 1), Q, op3.lower, op3.upper, None, 2, extra=8)
    assert problem.points_eval(1)(out)[3].min() > -1e-4 and v[0] < 1e-8

"""joint_limits, velocity_limits, acceleration and torque_limits on constructed OP3 motions."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate import examples
from motion2robot.validate.context import prepare
from motion2robot.validate.limits import (
    acceleration,
    joint_limits,
    torque_limits,
    velocity_limits,
)
from motion2robot.validate.options import CheckOptions


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def ctx_of(robot, q, fps=50.0, **opts):
    return prepare(RobotMotion(q, fps, robot.joint_names, robot.name), robot, CheckOptions(**opts))


def sine_joint(robot, joint, amp, hz, seconds=2.0, fps=50.0):
    q = np.tile(robot.nominal_qpos, (int(seconds * fps), 1))
    t = np.arange(len(q)) / fps
    q[:, 7 + robot.joint_index(joint)] += amp * np.sin(2 * np.pi * hz * t)
    return q


def test_joint_limits_pass_and_fail_with_the_excess(op3):
    assert joint_limits(ctx_of(op3, examples.standing(op3).qpos))["ok"]
    q = examples.standing(op3).qpos.copy()
    j = op3.joint_index("r_knee")
    q[30:35, 7 + j] = op3.lower[j] - 0.05
    out = joint_limits(ctx_of(op3, q))
    assert not out["ok"] and out["frames"] == [30, 31, 32, 33, 34]
    assert out["violations"][0]["joint"] == "r_knee"
    assert out["violations"][0]["by_rad"] == pytest.approx(0.05, abs=1e-6)
    assert out["violations"][0]["value_rad"] < out["violations"][0]["lower_rad"]


def test_velocity_limit_is_the_servo_speed(op3):
    slow = velocity_limits(ctx_of(op3, sine_joint(op3, "head_pan", 0.5, 1.0)))  # peak 3.1 rad/s
    assert slow["ok"] and 0.6 < slow["max_ratio"] < 0.7
    fast = velocity_limits(ctx_of(op3, sine_joint(op3, "head_pan", 1.0, 1.0)))  # peak 6.3 rad/s
    assert not fast["ok"]
    (v,) = fast["violations"]
    assert v["joint"] == "head_pan" and v["limit_rad_s"] == pytest.approx(4.8)
    assert v["peak_rad_s"] == pytest.approx(2 * np.pi, rel=0.02)
    # the margin option scales the limit
    assert velocity_limits(ctx_of(op3, sine_joint(op3, "head_pan", 1.0, 1.0), velocity_margin=1.5))["ok"]


def test_velocity_exactly_at_the_limit_passes(op3):
    q = examples.standing(op3).qpos.copy()
    j = 7 + op3.joint_index("head_pan")
    q[:, j] = np.clip(np.arange(len(q)) * 4.8 / 50.0, -1.5, 1.5)
    assert velocity_limits(ctx_of(op3, q))["ok"]


def test_acceleration_spike_fails(op3):
    smooth = acceleration(ctx_of(op3, sine_joint(op3, "l_el", 0.3, 1.0)))
    assert smooth["ok"]
    q = examples.standing(op3).qpos.copy()
    j = 7 + op3.joint_index("l_sho_pitch")
    q[40:, j] += 0.2 * np.arange(len(q) - 40) / 50.0 * 20  # a sudden 4 rad/s ramp
    out = acceleration(ctx_of(op3, q))
    assert not out["ok"] and out["violations"][0]["joint"] == "l_sho_pitch"
    assert set(out["frames"]) <= {39, 40, 41}
    assert out["violations"][0]["limit_rad_s2"] == pytest.approx(4.1 / op3.model.dof_armature[6 + op3.joint_index("l_sho_pitch")])


def test_torque_standing_is_feasible_and_a_fast_kick_is_not(op3):
    stand = torque_limits(ctx_of(op3, examples.standing(op3).qpos))
    assert stand["ok"] and 0.05 < stand["max_ratio"] < 0.5
    # knees carry the weight in the nominal crouch
    assert stand["worst_joint"] in ("l_knee", "r_knee", "l_ank_pitch", "r_ank_pitch", "l_hip_pitch", "r_hip_pitch")
    fast = torque_limits(ctx_of(op3, sine_joint(op3, "l_hip_roll", 0.25, 4.0)))  # 4 Hz leg shake
    assert not fast["ok"] and fast["violations"][0]["ratio"] > 1.0


def test_torque_margin_option_scales_the_limit(op3):
    ctx = ctx_of(op3, examples.standing(op3).qpos, torque_margin=0.05)
    out = torque_limits(ctx)
    assert not out["ok"] and out["max_ratio"] > 1.0

"""Physics playback: servo goals, standing stays up, a push over the heels falls."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate import examples
from motion2robot.validate.context import prepare
from motion2robot.validate.models import physics_model
from motion2robot.validate.options import CheckOptions
from motion2robot.validate.rollout import play, rollout, servo_calibration


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def test_playback_goals_are_the_guards_ticks(op3):
    """The servos get whole ticks inside the limits, at most the velocity limit's step per tick
    apart, settling on the first frame before the motion (a 1 rad jump of the left elbow in one
    frame is spread over ticks, and clipped to its range)."""
    q = examples.standing(op3, seconds=1.0).qpos.copy()
    j = op3.joint_index("l_el")
    q[25:, 7 + j] = op3.upper[j] + 0.5
    ctx = prepare(RobotMotion(q, 50.0, op3.joint_names, "op3"), op3, CheckOptions(stream_rate=100.0))
    pb = play(ctx)
    cal = servo_calibration(op3)
    order = [op3.joint_index(n) for n in cal.joints]
    ticks = cal.ticks_float(pb.goals[:, order])
    np.testing.assert_allclose(ticks, np.rint(ticks), atol=1e-6)
    assert (pb.goals <= np.asarray(op3.upper) + 1e-9).all() and (pb.goals >= np.asarray(op3.lower) - 1e-9).all()
    step = np.abs(np.diff(pb.goals[:, j]))
    tick = 1 / cal.ticks_per_rad  # the guard may round a step up by one tick
    assert 0.4 * op3.velocity_limit[j] / 100.0 < step.max() <= op3.velocity_limit[j] / 100.0 + tick + 1e-9
    assert pb.goal_rate == 100.0 and pb.goal_ticks == round(0.5 * 100) + 1  # settle 0.5 s, one ramp-in tick
    np.testing.assert_allclose(pb.goals[: pb.goal_ticks, j], q[0, 7 + j], atol=tick)
    assert pb.goals[-1, j] == pytest.approx(op3.upper[j], abs=tick)
    assert len(pb.goals) == pb.goal_ticks + 99  # 0.98 s of motion at 100 Hz: ticks 0..98


def test_physics_model_has_servo_actuators(op3):
    m = physics_model(op3)
    assert m.nu == op3.n_joints and m.opt.timestep <= 0.002
    np.testing.assert_allclose(m.actuator_gainprm[:, 0], op3.kp)
    np.testing.assert_allclose(m.actuator_forcerange[:, 1], op3.torque_limit)
    np.testing.assert_allclose(m.actuator_biasprm[:, 1], -op3.kp)


def test_standing_stays_up_and_tracks(op3):
    ctx = prepare(examples.standing(op3, seconds=1.0), op3, CheckOptions())
    out = rollout(ctx)
    assert out["ok"] and not out["fell"] and out["fall_time_s"] is None
    assert out["tracking_rms_mean_rad"] < 0.02
    assert out["root_drift_max_m"] < 0.02
    assert out["n_floor_contacts_other"] == 0


def test_falling_over_backwards_is_detected_with_its_time(op3):
    # the robot tipped 0.5 rad back about its heels from the first frame: it cannot stay there
    lean = examples.slow_lean(op3, angle=-0.45, lean_seconds=0.2, hold_seconds=1.3)
    q = np.repeat(lean.qpos[-1:], 60, axis=0)
    ctx = prepare(RobotMotion(q, 50, op3.joint_names, "op3"), op3, CheckOptions(settle_time=0.0))
    pb = play(ctx)
    assert pb.fall_frame is not None and pb.fall_cause in ("tilt", "height")
    out = rollout(ctx, pb)
    assert out["fell"] and out["fall_time_s"] < 1.2
    assert out["frames"][0] == pb.fall_frame
    assert np.isnan(pb.q[-1]).all()  # the playback stops after the fall
    assert any(e["event"] == "floor contact" for e in out["contact_events"])

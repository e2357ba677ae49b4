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
from motion2robot.validate.rollout import goals, play, rollout


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def test_goals_interpolate_clip_and_rate_limit():
    ref = np.array([[0.0], [1.0], [1.0]])  # a 1 rad jump in one 0.1 s frame
    g = goals(ref, fps=10.0, dt=0.01, vmax=np.array([5.0]), lower=np.array([-2.0]), upper=np.array([0.8]), settle_steps=3)
    assert g.shape == (3 + 21, 1)
    assert (g[:3] == 0).all()
    steps = np.diff(g[:, 0])
    assert steps.max() <= 5.0 * 0.01 + 1e-12  # never faster than the servo
    assert g[-1, 0] == pytest.approx(0.8)  # clipped to the range


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

"""The physics rollout of ``check`` and ``stream`` send the servos the same goals, tick for tick,
with and without sag compensation (real clip, stream loop on a simulated clock)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motion2robot.hardware.calibration import Calibration
from motion2robot.hardware.limits import JointLimits
from motion2robot.hardware.policy import TorquePolicy
from motion2robot.hardware.stream import stream_motion
from motion2robot.hardware.telemetry import read_telemetry
from motion2robot.robot import load_robot
from motion2robot.validate import CheckOptions, check
from motion2robot.validate.context import prepare
from motion2robot.validate.rollout import play
from motion2robot.validate.sag import compensated_motion
from tests._real_clips import WAVE, retargeted
from tests._shared import requires_shared

pytestmark = requires_shared


@pytest.fixture(scope="module")
def wave():
    """The first 1.5 s of the real wave on the OP3 (short keeps the test fast)."""
    m = retargeted(WAVE)
    return m.with_(qpos=m.qpos[: int(1.5 * m.fps)])


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


@pytest.fixture
def sim_clock(monkeypatch):
    """The stream loop on a simulated clock: every deadline is met exactly, no tick is missed."""
    now = [1000.0]

    def sleep_until(deadline, *args, interrupted=None, **kwargs):
        if interrupted is not None and interrupted():
            return False
        now[0] = max(now[0], deadline)
        return True

    monkeypatch.setattr("motion2robot.hardware.stream.clock", lambda: now[0])
    monkeypatch.setattr("motion2robot.hardware.stream.sleep_until", sleep_until)
    return now


def _stream_goals(telemetry_path, op3, phases=("ramp_in", "play")) -> np.ndarray:
    """Goal ticks of the ``phases`` ticks of a stream's telemetry, servo-map order."""
    tel = read_telemetry(telemetry_path)
    cal = Calibration.from_servo_map(op3.config.servos)
    rows = [t["cmd"] for t in tel.ticks if t["phase"] in phases]
    assert [t["i"] for t in tel.ticks] == list(range(len(tel.ticks)))  # no tick skipped
    return cal.to_ticks(np.array(rows))


def _rollout_goals(motion, op3, **opts) -> np.ndarray:
    pb = play(prepare(motion, op3, CheckOptions(**opts)))
    cal = Calibration.from_servo_map(op3.config.servos)
    order = [op3.joint_index(j) for j in cal.joints]
    settle = round(CheckOptions().settle_time * pb.goal_rate)
    return cal.to_ticks(pb.goals[settle:, order])


def _stream(motion, op3, path, rate):
    rep = stream_motion(motion, JointLimits.from_robot(op3), op3.config.servos, None, rate_hz=rate, dry_run=True,
                        telemetry_path=path, policy=TorquePolicy(on_end=0.0))
    assert rep.stop_reason == "end"
    return path


@pytest.mark.parametrize("rate", [100.0, 50.0])
def test_the_rollout_and_streams_guard_see_the_same_goals(op3, wave, sim_clock, tmp_path, rate):
    streamed = _stream_goals(_stream(wave, op3, tmp_path / "s.jsonl", rate), op3)
    rolled = _rollout_goals(wave, op3, stream_rate=rate)
    assert streamed.shape == rolled.shape and streamed.shape[0] == 1 + int((wave.num_frames - 1) / wave.fps * rate + 1e-9) + 1
    np.testing.assert_array_equal(streamed, rolled)


def test_sag_compensation_reaches_both_paths(op3, wave, sim_clock, tmp_path):
    plain = _rollout_goals(wave, op3)
    raised = _rollout_goals(wave, op3, sag_compensation=True)
    cal = Calibration.from_servo_map(op3.config.servos)
    knees = [cal.joints.index(j) for j in ("l_knee", "r_knee")]
    assert len(raised) > len(plain)  # the guard ramps in from the standing pose to the raised first goal
    k = len(plain) - 1  # play ticks (after one ramp-in tick without compensation)
    assert np.abs(raised[-k:] - plain[-k:])[:, knees].max() > 0.02 * cal.ticks_per_rad  # loaded knees: > 0.02 rad more
    # a dry run starts with the servos at the first goal, the rollout with the robot standing in
    # the planned first frame: the ramp-ins differ, the play ticks are the same
    streamed = _stream_goals(_stream(compensated_motion(wave, op3), op3, tmp_path / "c.jsonl", 100.0), op3, ("play",))
    assert len(streamed) == k
    np.testing.assert_array_equal(streamed, raised[-k:])


def test_sag_compensation_through_both_clis(op3, wave, sim_clock, tmp_path, capsys):
    """``check --sag-compensation`` plays it and says so; ``stream --sag-compensation`` sends the
    goals that playback used."""
    from motion2robot.cli import main

    path = wave.save(tmp_path / "wave.npz")
    for flag in ([], ["--sag-compensation"]):
        out = tmp_path / f"report{len(flag)}.json"
        assert main(["check", str(path), "--json", str(out), *flag]) in (0, 1)
        roll = json.loads(out.read_text())["checks"]["rollout"]
        assert roll["sag_compensation"] is bool(flag) and roll["stream_rate_hz"] == 100.0
        assert "tracking_rms_mean_rad" in roll
    tel = tmp_path / "wave.telemetry.jsonl"
    assert main(["stream", str(path), "--dry-run", "--sag-compensation", "--rest", "last", "--on-end", "off",
                 "--telemetry", str(tel)]) == 0
    assert "sag compensation: goals raised by up to" in capsys.readouterr().out
    streamed = _stream_goals(tel, op3, ("play",))
    np.testing.assert_array_equal(streamed, _rollout_goals(wave, op3, sag_compensation=True)[-len(streamed):])


def test_sag_compensation_tracks_the_plan_closer_on_a_real_clip(op3, wave):
    """Feeding the sag forward brings the simulated joints closer to the planned ones."""
    off = check(wave, op3, CheckOptions()).checks["rollout"]
    on = check(wave, op3, CheckOptions(sag_compensation=True)).checks["rollout"]
    assert not off["fell"] and not on["fell"]
    assert on["tracking_rms_mean_rad"] < 0.7 * off["tracking_rms_mean_rad"]

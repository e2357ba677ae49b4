"""The tick schedule stream and the physics rollout share: play times, ramp-in, play goals."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.hardware.calibration import Calibration
from motion2robot.hardware.goals import goal_sequence, play_target, play_targets, play_ticks, play_time
from motion2robot.hardware.guard import SafetyGuard
from motion2robot.hardware.limits import JointLimits
from motion2robot.robot.servo_map import ServoMap, ServoSpec

CAL = Calibration.from_servo_map(ServoMap("XM430-W350", 1_000_000, 4096, 2048, (ServoSpec("a", 1), ServoSpec("b", 2, -1, 40))))
LIM = JointLimits(("a", "b"), [-1.0, -1.0], [1.0, 1.0], [2.0, 2.0])


def test_play_time_is_counted_in_ticks_and_ends_or_wraps():
    assert play_time(0, 100.0, 1.0) == 0.0 and play_time(50, 100.0, 1.0) == pytest.approx(0.5)
    assert play_time(100, 100.0, 1.0) == pytest.approx(1.0) and play_time(101, 100.0, 1.0) is None
    assert play_time(130, 100.0, 1.0, loop=True) == pytest.approx(0.3)
    assert play_ticks(51, 50.0, 100.0) == 101 and play_ticks(11, 30.0, 100.0) == 34  # 1/3 s: ticks 0..33


def test_play_target_interpolates_the_frames():
    traj = np.array([[0.0, 0.0], [1.0, -1.0], [1.0, 1.0]])
    np.testing.assert_allclose(play_target(traj, 10.0, 100.0, 5), [0.5, -0.5])
    np.testing.assert_allclose(play_target(traj, 10.0, 100.0, 15), [1.0, 0.0])
    assert play_target(traj, 10.0, 100.0, 21) is None


def test_goal_sequence_ramps_in_then_plays_every_tick():
    """From 0.3 rad away the guard ramps in at 0.5 rad/s (0.005 rad per tick at 100 Hz), then
    plays one goal per tick, each the guard's rounding of the motion at that tick's time."""
    traj = np.stack([np.linspace(0.3, 0.5, 11), np.linspace(-0.2, 0.0, 11)], axis=1)  # 1 s at 10 fps
    guard = SafetyGuard(LIM, CAL, 100.0, ramp_speed=0.5)
    seq = goal_sequence(guard, traj, 10.0, 100.0, CAL.to_ticks(np.zeros(2)))
    assert np.array_equal(seq.start, CAL.to_ticks(np.zeros(2)))
    # 196 ticks at 3.26 ticks per tick (whole ticks: 3, or 3.26 on average where the guard carries fractions)
    assert 60 <= len(seq.ramp) <= 66
    assert np.array_equal(seq.ramp[-1], CAL.to_ticks(traj[0]))
    assert len(seq.play) == 101 and seq.ticks.shape == (len(seq.ramp) + 101, 2)
    expect = CAL.to_ticks(np.array([play_target(traj, 10.0, 100.0, k) for k in range(101)]))
    np.testing.assert_array_equal(seq.play, expect)
    again = goal_sequence(SafetyGuard(LIM, CAL, 100.0, ramp_speed=0.5), traj, 10.0, 100.0, CAL.to_ticks(traj[0]))
    assert len(again.ramp) == 1 and np.array_equal(again.play, seq.play)  # already there: one ramp-in tick


@pytest.mark.parametrize("speed", [0.3, 1.9, 6.0])
def test_goals_at_once_are_the_goals_tick_by_tick(speed):
    """``guard.goals`` gives the goals of one ``next_goal`` per tick, and leaves the guard where
    they leave it (its next goals alike): for a motion well under the velocity limit (2 rad/s),
    one just under it (moves of up to the 13 whole ticks a tick earns: the budget decides to the
    last bit) and one beyond it (the guard limits, tick by tick), with a NaN target held."""
    rng = np.random.default_rng(7)
    t = np.arange(300) / 100.0
    traj = np.stack([0.6 * np.sin(speed * t / 0.6), -0.5 * np.cos(speed * t / 0.5) + 0.3], axis=1)
    traj += 1e-4 * rng.standard_normal(traj.shape)
    if speed == 6.0:
        traj[40, 1] = np.nan
    a, b = SafetyGuard(LIM, CAL, 100.0), SafetyGuard(LIM, CAL, 100.0)
    a.start(CAL.to_ticks(traj[0])), b.start(CAL.to_ticks(traj[0]))
    at_once = a.goals(traj[:200])
    one_by_one = np.array([b.next_goal(row) for row in traj[:200]])
    np.testing.assert_array_equal(at_once, one_by_one)
    np.testing.assert_array_equal(a.budget, b.budget)
    np.testing.assert_array_equal(a.goals(traj[200:]), [b.next_goal(row) for row in traj[200:]])
    moves = np.abs(np.diff(one_by_one, axis=0)).max(axis=0)
    assert (moves <= a.step_max).all()  # the speed limit held either way
    if speed == 6.0:  # beyond the limit: the guard lagged behind the targets
        assert np.abs(one_by_one - CAL.to_ticks(np.nan_to_num(traj[:200]))).max() > 50


def test_play_targets_are_play_target_of_every_tick():
    traj = np.array([[0.0, 0.0], [1.0, -1.0], [1.0, 1.0], [0.2, np.nan]])
    for fps, rate in ((10.0, 100.0), (30.0, 100.0), (7.0, 50.0)):
        rows = play_targets(traj, fps, rate)
        expect = [play_target(traj, fps, rate, k) for k in range(play_ticks(len(traj), fps, rate))]
        np.testing.assert_array_equal(rows, expect)

"""What goal each servo gets at each control tick: the one schedule that ``stream`` sends and the
physics rollout of ``check`` plays.

A stream runs at ``rate_hz`` control ticks per second and every goal goes through the
:class:`~motion2robot.hardware.guard.SafetyGuard` (tick rounding, joint limits, step per tick):

- start: the guard accepts the servos' present pose (ticks) as the first goal;
- ramp-in: each tick steps towards the motion's first frame at the ramp speed, until the guard
  has reached it (at least one tick, even when the servos already stand there);
- play: the k-th play tick (k = 0, 1, ...) asks for the motion at ``k / rate_hz`` seconds,
  linearly interpolated between frames (:func:`~motion2robot.hardware.trajectory.sample`);
  the motion ends after the last tick at or before its duration (or wraps round when looping).

Play time is counted in ticks, not read from the wall clock, so the same motion at the same rate
always gets the same goals; a tick the loop misses (an overrun) is skipped, and the next one asks
for the motion at that later tick's time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2robot.hardware.guard import SafetyGuard
from motion2robot.hardware.trajectory import sample, sample_times

#: Ticks the ramp-in may take before :func:`goal_sequence` gives up (a guard that never reaches
#: its target is a bug, not a slow ramp: 100,000 ticks at 100 Hz are 17 minutes).
MAX_RAMP_TICKS = 100_000


def play_time(k: int, rate_hz: float, duration: float, loop: bool = False) -> float | None:
    """Motion time (s) of play tick ``k`` at ``rate_hz``; None once a motion of ``duration`` s
    has ended (with ``loop``, the time wraps round instead)."""
    t = k / rate_hz
    if t <= duration + 1e-9:
        return min(t, duration)
    if loop and duration > 0:
        return t % duration
    return None


def play_target(traj: np.ndarray, fps: float, rate_hz: float, k: int, loop: bool = False) -> np.ndarray | None:
    """Joint targets (rad, (n,)) of play tick ``k`` for a (T, n) trajectory at ``fps``; None
    after the end."""
    t = play_time(k, rate_hz, (traj.shape[0] - 1) / fps, loop)
    return None if t is None else sample(traj, fps, t)


def play_ticks(num_frames: int, fps: float, rate_hz: float) -> int:
    """Number of play ticks of a motion of ``num_frames`` frames at ``fps`` (no loop)."""
    return int(np.floor((num_frames - 1) / fps * rate_hz + 1e-9)) + 1


def play_targets(traj: np.ndarray, fps: float, rate_hz: float) -> np.ndarray:
    """The joint targets (rad, (K, n)) of every play tick of ``traj`` (no loop): row k is
    :func:`play_target` of tick k, the same numbers."""
    k = np.arange(play_ticks(traj.shape[0], fps, rate_hz))
    return sample_times(traj, fps, np.minimum(k / rate_hz, (traj.shape[0] - 1) / fps))


@dataclass(frozen=True, eq=False)
class GoalSequence:
    """Goals in servo ticks, (n,) or (K, n) int64 in the guard's joint order: ``start`` (the
    present pose accepted), ``ramp`` (R >= 1 ramp-in ticks), ``play`` (one row per play tick)."""

    start: np.ndarray
    ramp: np.ndarray
    play: np.ndarray

    @property
    def ticks(self) -> np.ndarray:
        """Every goal sent after the start, tick by tick: ramp-in then play, (R + K, n)."""
        return np.concatenate([self.ramp, self.play])


def goal_sequence(guard: SafetyGuard, traj: np.ndarray, fps: float, rate_hz: float,
                  present: np.ndarray) -> GoalSequence:
    """The goals a stream sends for ``traj`` ((T, n) rad in the guard's joint order, at ``fps``)
    when the servos start at ``present`` (ticks) and no tick is missed (see the module docstring)."""
    start = guard.start(present)
    ramp = []
    while True:
        ramp.append(guard.next_goal(traj[0], ramp=True))
        if guard.reached(traj[0]):
            break
        if len(ramp) >= MAX_RAMP_TICKS:
            raise RuntimeError("goal_sequence: the guard never reached the first frame")
    play = guard.goals(play_targets(traj, fps, rate_hz))
    return GoalSequence(start, np.asarray(ramp, dtype=np.int64), play)

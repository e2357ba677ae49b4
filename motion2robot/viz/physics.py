"""The physics rollout as full robot poses (root + hinges per motion frame), for playing it back.

Prefers the rollout recorded by the feasibility checks (``report.series["rollout_qpos"]``,
(T, 7 + n)); otherwise runs that playback (:func:`motion2robot.validate.rollout.play`: the
servos get the goals ``stream`` would send, starting at rest on frame 0 after the settle time).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion


def _fill_nan_rows(q: np.ndarray) -> np.ndarray:
    """Rows not recorded (NaN, after the playback stopped) repeat the last recorded row."""
    q = np.array(q, dtype=float)
    ok = ~np.isnan(q).any(axis=1)
    if not ok.any():
        raise ValueError("the physics rollout recorded no frame")
    last = np.maximum.accumulate(np.where(ok, np.arange(len(q)), -1))
    first = int(np.argmax(ok))
    last[last < 0] = first
    return q[last]


def rollout_qpos(motion: RobotMotion, robot: Robot, report: Any = None) -> np.ndarray:
    """(T, nq) simulated poses at the motion's frames (metres, wxyz, radians)."""
    series = getattr(report, "series", None) or {}
    rec = series.get("rollout_qpos")
    if rec is not None and np.shape(rec) == motion.qpos.shape:
        return _fill_nan_rows(rec)
    return simulate(motion, robot)


def simulate(motion: RobotMotion, robot: Robot) -> np.ndarray:
    """Run the checks' physics playback (servos driven as ``stream`` drives them, default check
    options) and return the full pose at each motion frame; frames after the playback stopped
    (a fall) repeat the last recorded pose."""
    from motion2robot.validate.context import prepare
    from motion2robot.validate.options import CheckOptions
    from motion2robot.validate.rollout import play

    return _fill_nan_rows(play(prepare(motion, robot, CheckOptions())).qpos)

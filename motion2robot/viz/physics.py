"""The physics rollout as full robot poses (root + hinges per motion frame), for playing it back.

Prefers the rollout recorded by the feasibility checks (``report.series["rollout_qpos"]``,
(T, 7 + n)); otherwise runs the same playback from the checks' building blocks
(:func:`motion2robot.validate.models.physics_model`, :func:`motion2robot.validate.rollout.goals`):
servo-like position actuators fed the motion, starting at rest on frame 0 after the settle time.
"""

from __future__ import annotations

from typing import Any

import mujoco
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
    """Run the checks' physics playback and record the full pose at each motion frame."""
    from motion2robot.validate.models import physics_model
    from motion2robot.validate.options import CheckOptions
    from motion2robot.validate.rollout import goals

    opts = CheckOptions()
    m = physics_model(robot, opts.timestep)
    d = mujoco.MjData(m)
    dt = m.opt.timestep
    settle = int(round(opts.settle_time / dt))
    ctrl = goals(motion.joints, motion.fps, dt, np.asarray(robot.velocity_limit), np.asarray(robot.lower),
                 np.asarray(robot.upper), settle)
    record_at = settle + np.round(np.arange(motion.num_frames) / (motion.fps * dt)).astype(int)
    d.qpos[:] = motion.qpos[0]
    mujoco.mj_forward(m, d)
    out = np.empty_like(motion.qpos)
    f = 0
    for s in range(ctrl.shape[0]):
        while f < motion.num_frames and record_at[f] == s:
            out[f] = d.qpos
            f += 1
        d.ctrl[:] = ctrl[s]
        mujoco.mj_step(m, d)
    out[f:] = d.qpos
    return out

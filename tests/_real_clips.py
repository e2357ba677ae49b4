"""Robot motions made from real clips of ../shared/motions, for the tests that judge them."""

from __future__ import annotations

import functools

import numpy as np

from motion2robot.robot_motion import RobotMotion
from tests._shared import MOTIONS

#: A short real clip: a person waving goodbye while standing (Bandai Namco, 30 fps).
WAVE = "bvh/bandai_byebye_normal_001.bvh"
LEG_WORDS = ("hip", "knee", "ank")


@functools.lru_cache(maxsize=4)
def retargeted(name: str, robot_name: str = "op3") -> RobotMotion:
    """The clip ``name`` (relative to ../shared/motions) retargeted with the default options."""
    from motion2robot.motion import read_motion
    from motion2robot.retarget import retarget
    from motion2robot.robot import load_robot

    assert MOTIONS is not None
    return retarget(read_motion(MOTIONS / name)[0], load_robot(robot_name))


def standing_wave(robot, seconds: float | None = None) -> RobotMotion:
    """The real wave with the root and the legs held at their first retargeted frame: both soles
    stay exactly where they are while the arms and head move as the person's did."""
    m = retargeted(WAVE, robot.name)
    q = m.qpos.copy() if seconds is None else m.qpos[: int(round(seconds * m.fps)) + 1].copy()
    legs = [7 + i for i, n in enumerate(robot.joint_names) if any(w in n for w in LEG_WORDS)]
    q[:, :7] = q[0, :7]
    q[:, legs] = q[0, legs]
    return RobotMotion(q, m.fps, robot.joint_names, robot.name)


def yaw_about(motion: RobotMotion, centre: np.ndarray, rate: float) -> RobotMotion:
    """``motion`` turned about the vertical through ``centre`` (x, y m) at ``rate`` rad/s."""
    q = motion.qpos.copy()
    th = rate * np.arange(len(q)) / motion.fps
    c, s = np.cos(th), np.sin(th)
    d = q[:, :2] - centre
    q[:, 0] = centre[0] + c * d[:, 0] - s * d[:, 1]
    q[:, 1] = centre[1] + s * d[:, 0] + c * d[:, 1]
    w, x, y, z = q[:, 3:7].T
    hw, hz = np.cos(th / 2), np.sin(th / 2)  # (hw, 0, 0, hz) * (w, x, y, z)
    q[:, 3:7] = np.stack([hw * w - hz * z, hw * x - hz * y, hw * y + hz * x, hw * z + hz * w], axis=1)
    return RobotMotion(q, motion.fps, motion.joint_names, motion.robot)

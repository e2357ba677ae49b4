"""The requested trajectory (``meta["control_path"]`` of the human clip) carried onto the robot.

The retargeter scales the human's pelvis path by the ``legs`` ratio into the robot's world; the
control path is scaled the same way, so the robot's root can be compared with it in robot metres
and, divided by the ratio, in human metres (:func:`motion2robot.validate.trajectory.trajectory`).
The path is carried onto the robot's frames by time: a slowed tempo stretches it like the motion, and
an output rate other than the human clip's (``retarget --fps``) resamples it the same way the
retargeter resamples the motion (robot frame r at r / fps human seconds).
"""

from __future__ import annotations

import numpy as np

from motion2robot.motion.human import HumanMotion
from motion2robot.robot_motion import RobotMotion


def on_robot_frames(path: list, frames: int, robot_fps: float, human_fps: float, tempo: float = 1.0) -> list:
    """The per-frame path on ``frames`` robot frames: robot frame r is at human time
    r / (robot_fps * tempo) seconds (``retarget --fps`` resamples, a slowed tempo stretches), so
    human frame u = that time * human_fps; linear interpolation between the two nearest human
    frames, None unless both are controlled."""
    if len(path) == frames and abs(robot_fps * tempo - human_fps) < 1e-9:
        return path
    out = []
    last = len(path) - 1
    for r in range(frames):
        u = r * human_fps / (robot_fps * tempo)
        u = min(u, last)  # the stretch holds the last frame like this
        a, b = int(np.floor(u)), int(np.ceil(u))
        if path[a] is None or path[b] is None:
            out.append(None)
        else:
            w = u - a
            out.append([(1 - w) * path[a][0] + w * path[b][0], (1 - w) * path[a][1] + w * path[b][1]])
    return out


def with_control_path(motion: RobotMotion, human: HumanMotion | None) -> RobotMotion:
    """``motion`` with ``meta["control_xy"]`` (per frame [x, y] robot metres or None) and
    ``meta["control_scale"]`` when the human clip carries a control path; else ``motion`` itself."""
    path = None if human is None else human.meta.get("control_path")
    if not path or len(path) < 2:
        return motion
    legs = float(motion.meta.get("scale", {}).get("legs", 1.0))
    tempo = float(motion.meta.get("tempo", 1.0) or 1.0)
    frames = on_robot_frames(path, motion.num_frames, motion.fps, human.fps, tempo)
    xy = [None if p is None else [p[0] * legs, p[1] * legs] for p in frames]
    return motion.with_(meta={"control_xy": xy, "control_scale": legs,
                              "control_source": human.meta.get("control_source")})

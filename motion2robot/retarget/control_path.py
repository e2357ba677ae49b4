"""The requested trajectory (``meta["control_path"]`` of the human clip) carried onto the robot.

The retargeter scales the human's pelvis path by the ``legs`` ratio into the robot's world; the
control path is scaled the same way, so the robot's root can be compared with it in robot metres
and, divided by the ratio, in human metres (:func:`motion2robot.validate.trajectory.trajectory`).
A slowed tempo stretches the path over the robot's frames like the motion.
"""

from __future__ import annotations

import numpy as np

from motion2robot.motion.human import HumanMotion
from motion2robot.robot_motion import RobotMotion


def _stretched(path: list, frames: int) -> list:
    """The per-frame path on ``frames`` robot frames (a slowed tempo stretches the clip): linear
    interpolation between the two nearest human frames, None unless both are controlled."""
    if len(path) == frames:
        return path
    out = []
    for r in range(frames):
        u = r * (len(path) - 1) / max(frames - 1, 1)
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
    xy = [None if p is None else [p[0] * legs, p[1] * legs] for p in _stretched(path, motion.num_frames)]
    return motion.with_(meta={"control_xy": xy, "control_scale": legs,
                              "control_source": human.meta.get("control_source")})

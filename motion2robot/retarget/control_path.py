"""The requested trajectory (``meta["control_path"]`` of the human clip) carried onto the robot.

The retargeter scales the human's pelvis path by the ``legs`` ratio into the robot's world; the
control path is scaled the same way, so the robot's root can be compared with it in robot metres
and, divided by the ratio, in human metres (:func:`motion2robot.validate.trajectory.trajectory`).
"""

from __future__ import annotations

from motion2robot.motion.human import HumanMotion
from motion2robot.robot_motion import RobotMotion


def with_control_path(motion: RobotMotion, human: HumanMotion | None) -> RobotMotion:
    """``motion`` with ``meta["control_xy"]`` (per frame [x, y] robot metres or None) and
    ``meta["control_scale"]`` when the human clip carries a control path; else ``motion`` itself."""
    path = None if human is None else human.meta.get("control_path")
    if not path or len(path) != motion.num_frames:
        return motion
    legs = float(motion.meta.get("scale", {}).get("legs", 1.0))
    xy = [None if p is None else [p[0] * legs, p[1] * legs] for p in path]
    return motion.with_(meta={"control_xy": xy, "control_scale": legs,
                              "control_source": human.meta.get("control_source")})

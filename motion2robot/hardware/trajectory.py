"""Joint trajectories for streaming: pick the servo joints out of a motion, sample it in time."""

from __future__ import annotations

import numpy as np

from motion2robot.errors import InputFileError
from motion2robot.robot_motion import RobotMotion


def sample(traj: np.ndarray, fps: float, t: float) -> np.ndarray:
    """Linear interpolation of ``traj`` (T, n) at time ``t`` s (clamped to the ends); NaN stays NaN."""
    f = min(max(t * fps, 0.0), traj.shape[0] - 1.0)
    i = int(f)
    a = f - i
    if a == 0.0 or i + 1 >= traj.shape[0]:
        return traj[i].copy()
    return (1.0 - a) * traj[i] + a * traj[i + 1]


def joint_trajectory(motion: RobotMotion, joints: tuple[str, ...]) -> np.ndarray:
    """(T, n) hinge angles of ``joints`` picked out of the motion by name."""
    idx = {n: i for i, n in enumerate(motion.joint_names)}
    missing = [j for j in joints if j not in idx]
    if missing:
        raise InputFileError(f"the motion has no joints {', '.join(missing)} that the servo map drives; "
                             f"retarget it for robot '{motion.robot}' or use the matching --robot")
    return motion.joints[:, [idx[j] for j in joints]]

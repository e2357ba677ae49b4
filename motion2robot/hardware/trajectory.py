"""Joint trajectories for streaming: pick the servo joints out of a motion, sample it in time."""

from __future__ import annotations

import numpy as np

from motion2robot.errors import InputFileError
from motion2robot.robot_motion import RobotMotion


def sample(traj: np.ndarray, fps: float, t: float) -> np.ndarray:
    """Linear interpolation of ``traj`` (T, n) at time ``t`` s (clamped to the ends); NaN stays NaN."""
    return sample_times(traj, fps, np.array([t], dtype=np.float64))[0]


def sample_times(traj: np.ndarray, fps: float, times: np.ndarray) -> np.ndarray:
    """:func:`sample` at each of ``times`` (K,) s: (K, n), every row the same numbers."""
    traj = np.asarray(traj)
    f = np.minimum(np.maximum(np.asarray(times, dtype=np.float64) * fps, 0.0), traj.shape[0] - 1.0)
    i = f.astype(np.int64)
    a = (f - i)[:, None]
    j = np.minimum(i + 1, traj.shape[0] - 1)
    at_frame = (a == 0.0) | (i + 1 >= traj.shape[0])[:, None]
    return np.where(at_frame, traj[i], (1.0 - a) * traj[i] + a * traj[j])


def joint_trajectory(motion: RobotMotion, joints: tuple[str, ...]) -> np.ndarray:
    """(T, n) hinge angles of ``joints`` picked out of the motion by name."""
    idx = {n: i for i, n in enumerate(motion.joint_names)}
    missing = [j for j in joints if j not in idx]
    if missing:
        raise InputFileError(f"the motion has no joints {', '.join(missing)} that the servo map drives; "
                             f"retarget it for robot '{motion.robot}' or use the matching --robot")
    return motion.joints[:, [idx[j] for j in joints]]

"""How near a robot motion is to the human motion it was made from: the figure the legs policy
compares two passing legs modes by (:func:`~motion2robot.retarget.executable.plan`).

The figure is the one ``score`` reports as fidelity: the mean distance (m, at the robot's scale,
world frame, z up) between the robot's keypoint sites and the human's keypoints scaled to the
robot (:func:`~.scale.scaled_keypoints`), over frames and keypoints. Both modes are measured
against the same targets, the human's at the attempt's tempo with the scale computed from that
human (a ``stance`` attempt's own setup tracks the stanced legs, so its solver residual is not
comparable with a ``steps`` attempt's).
"""

from __future__ import annotations

import numpy as np

from motion2robot.motion.human import KP, HumanMotion
from motion2robot.retarget.scale import Scale, auto_scale, scaled_keypoints
from motion2robot.robot.poses import frame_poses
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion


def mean_distance(robot_kp: np.ndarray, human_kp: np.ndarray) -> float:
    """Mean distance (m) between (T, K, 3) robot and scaled human keypoints."""
    return float(np.linalg.norm(robot_kp - human_kp, axis=-1).mean())


def centred(kp: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """(T, K, 3) keypoints relative to the pelvis keypoint (or to their centroid without one)."""
    centre = kp[:, [names.index("pelvis")]] if "pelvis" in names else kp.mean(axis=1, keepdims=True)
    return kp - centre


def keypoint_error(motion: RobotMotion, human: HumanMotion, robot: Robot, scale: Scale | None = None,
                   pose: bool = False) -> float:
    """Mean distance (m) between ``motion``'s keypoint sites and ``human``'s keypoints scaled by
    ``scale`` (default: :func:`~.scale.auto_scale` of ``human``), frame by frame (``motion`` at
    ``human``'s rate and tempo; the shorter of the two sets the frames compared). ``pose``: both
    taken relative to their pelvis keypoint (:func:`centred`: the posture alone, not where it is)."""
    scale = scale or auto_scale(human, robot)
    T = min(motion.num_frames, human.num_frames)
    sites = frame_poses(robot.model, motion.qpos[:T], robot.keypoint_sites).sites
    target = scaled_keypoints(np.asarray(human.positions)[:T], scale)[:, [KP[k] for k in robot.keypoints]]
    if pose:
        sites, target = centred(sites, robot.keypoints), centred(target, robot.keypoints)
    return mean_distance(sites, target)

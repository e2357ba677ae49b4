"""How near a robot motion is to the human motion it was made from: the figure the legs policy
compares two passing legs modes by (:func:`~motion2robot.retarget.executable.plan`).

The figure is the one ``score`` reports as fidelity: the mean distance (m, at the robot's scale,
world frame, z up) between the robot's keypoint sites and the human's keypoints scaled to the
robot (:func:`~.scale.scaled_keypoints`), over frames and keypoints. Both modes are measured
against the same targets, the human's at the attempt's tempo with the scale computed from that
human (a ``stance`` attempt's own setup tracks the stanced legs, so its solver residual is not
comparable with a ``steps`` attempt's). :func:`compare` makes the policy's comparison,
:func:`nearness_words` says what it found in the fallback's words.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from motion2robot.motion.human import KP, HumanMotion
from motion2robot.retarget.footholds import PatternError
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


def compare(stance: RobotMotion, steps: Callable[[], RobotMotion], tempo: float, human: HumanMotion,
             robot: Robot) -> dict:
    """What the ``stance`` and the steps (``steps()``) of one tempo measure against ``human`` (the
    human at that tempo; :func:`keypoint_error`): {"tempo", "keypoint_error_m":
    {mode: m}}, or {"tempo", "steps": why} when the clip gives no walking pattern."""
    figures: dict = {"tempo": tempo}
    try:
        steps = steps()
    except PatternError as err:  # a foot never down: no pattern to compare
        return {**figures, "steps": str(err)}
    error = {"stance": keypoint_error(stance, human, robot), "steps": keypoint_error(steps, human, robot)}
    return {**figures, "keypoint_error_m": {k: round(v, 5) for k, v in error.items()}}


def steps_nearer(nearness: dict | None) -> bool:
    error = (nearness or {}).get("keypoint_error_m")
    return bool(error) and error["steps"] < error["stance"]


def nearness_words(nearness: dict | None, legs: str, factor: float) -> list[str]:
    """The fallback's words on the comparison of :func:`compare` (none when there was none, or
    the steps were nearer but failed: the attempts say so)."""
    error = (nearness or {}).get("keypoint_error_m")
    if not error:
        return []
    cm = (f"keypoint error {100 * error['steps']:.1f} cm vs the stance's {100 * error['stance']:.1f} cm"
          + (" after its solves" if nearness.get("stance_measured") == "solves" else ""))
    at = f"x{nearness['tempo']:.2f}"
    if not steps_nearer(nearness):
        return [f"steps at {at} are farther from the human ({cm})"]
    if legs == "steps" and factor == nearness["tempo"]:
        return [f"the steps at {at} are nearer to the human than the stance, which goes first for its tempo ({cm})"]
    return []

"""How faithfully a robot motion performs the human motion it was made from.

Three figures per sample, all measured on the final robot motion (after the tempo and legs policy):

- **keypoint error**: mean over frames and tracked keypoints of the distance between the robot's
  keypoint site (MuJoCo forward kinematics) and the human keypoint scaled to the robot (the
  retargeter's own :func:`~motion2robot.retarget.scale.scaled_keypoints` with the scale it used),
  in robot metres and, divided by the legs ratio, in human metres. The human is the clip as given
  (played at the chosen tempo): with the ``stance`` fallback the error includes the legs the robot
  did not perform and the path it did not walk. ``keypoint_error_pose_m`` is the same with both
  skeletons' pelvis keypoints (or keypoint centroids) put together in every frame: the posture
  alone, without the root's path.
- **contact agreement**: share of (frame, foot) pairs where the robot's foot is in contact exactly
  when the human's is. Human labels: the clip's own (263-d features) or detected from foot height
  and speed (:func:`~motion2robot.retarget.contacts.contact_labels`), mapped onto the robot's frames
  through the tempo factor. Robot contact: a sole corner within ``contact_height`` of the floor and
  slower than ``contact_speed`` horizontally (the thresholds of the checks' support test, without
  the contact labels the retargeter used, so the figure is measured, not copied).
- **trajectory error** (clips with a requested root path only): the ``trajectory`` check's
  ``control_*`` figures, already in the batch row's ``control``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from motion2robot.motion.human import KP, HumanMotion
from motion2robot.motion.ops import resample
from motion2robot.retarget.nearness import centred
from motion2robot.retarget.nearness import mean_distance as keypoint_error  # one definition for score and the policy
from motion2robot.robot.poses import frame_poses
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion

#: Keys of the ``fidelity`` dict of a result row.
FIELDS = ("keypoint_error_m", "keypoint_error_human_m", "keypoint_error_pose_m", "contact_agreement",
          "contact_frames_human", "contact_frames_robot", "contact_labels")


def robot_points(motion: RobotMotion, robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """World positions (m) per frame of the robot's keypoint sites (T, K, 3), in the order of
    ``robot.keypoints``, and of its sole corners (T, 2, 4, 3) [left, right]."""
    kp_sites = np.asarray(robot.keypoint_sites)
    sites = frame_poses(robot.model, motion.qpos, np.r_[kp_sites, np.asarray(robot.sole_sites).ravel()]).sites
    return sites[:, :len(kp_sites)], sites[:, len(kp_sites):].reshape(len(sites), 2, 4, 3)


def robot_contacts(corners: np.ndarray, fps: float, height: float, speed: float) -> np.ndarray:
    """(T, 2) bool: a foot is in contact when one of its sole corners is below ``height`` (m) and
    moves slower than ``speed`` (m/s) horizontally (central differences)."""
    if len(corners) > 1:
        vel = np.gradient(corners[..., :2], axis=0) * fps
    else:
        vel = np.zeros_like(corners[..., :2])
    low = corners[..., 2] < height
    slow = np.linalg.norm(vel, axis=-1) < speed
    return (low & slow).any(axis=2)


def tempo_index(robot_frames: int, human_frames: int, factor: float) -> np.ndarray:
    """Nearest human frame of every robot frame of a motion played ``factor`` times slower
    (the frame map of :func:`~motion2robot.retarget.tempo.stretch`)."""
    u = np.arange(robot_frames) / max(factor, 1e-9)
    return np.clip(np.rint(u).astype(int), 0, human_frames - 1)


def contact_agreement(robot: np.ndarray, human: np.ndarray) -> float:
    """Share (0-1) of (frame, foot) pairs where the (T, 2) bool labels agree."""
    return float(np.mean(np.asarray(robot, dtype=bool) == np.asarray(human, dtype=bool)))


def _scale(meta: dict[str, Any]) -> Any:
    from motion2robot.retarget.scale import Scale

    s = meta["scale"]
    return Scale(legs=float(s["legs"]), arms=float(s["arms"]), height=float(s["height"]),
                 source=tuple(sorted((s.get("source") or {}).items())))


def fidelity(human: HumanMotion, motion: RobotMotion, robot: Robot, *, fps: float | None = None,
             contact_height: float = 0.01, contact_speed: float = 0.3) -> dict[str, Any]:
    """The fidelity figures (see the module text) of ``motion``, made from ``human`` (resampled to
    ``fps`` first when the retargeter was asked to) on ``robot``."""
    from motion2robot.retarget.contacts import contact_labels
    from motion2robot.retarget.scale import scaled_keypoints
    from motion2robot.retarget.tempo import stretch

    if fps is not None and abs(fps - human.fps) > 1e-9:
        human = resample(human, fps)
    factor = float(motion.meta.get("tempo", 1.0))
    scale = _scale(motion.meta)
    played = stretch(human, factor)
    kp_r, corners = robot_points(motion, robot)
    T = min(len(kp_r), played.num_frames)  # equal unless the motion was cut after the retarget
    target = scaled_keypoints(played.positions[:T], scale)[:, [KP[k] for k in robot.keypoints]]
    err = keypoint_error(kp_r[:T], target)
    pose = keypoint_error(centred(kp_r[:T], robot.keypoints), centred(target, robot.keypoints))
    labels, source = contact_labels(human)
    human_c = labels[tempo_index(motion.num_frames, human.num_frames, factor)]
    robot_c = robot_contacts(corners, motion.fps, contact_height, contact_speed)
    return {
        "keypoint_error_m": round(err, 5),
        "keypoint_error_human_m": round(err / scale.legs, 5),
        "keypoint_error_pose_m": round(pose, 5),
        "contact_agreement": round(contact_agreement(robot_c, human_c), 5),
        "contact_frames_human": int(human_c.sum()),
        "contact_frames_robot": int(robot_c.sum()),
        "contact_labels": source,
    }

"""The robot's motion mapped back onto the human skeleton (steps 1-4 of
:mod:`motion2robot.projection`): MuJoCo forward kinematics of the robot's keypoints, then the
pure maths of :mod:`~motion2robot.projection.maths`."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from motion2robot.errors import UserError
from motion2robot.motion.human import KP, SMPL22, HumanMotion
from motion2robot.projection.maths import fill_torso, robot_frames, unscale
from motion2robot.retarget.retime import sample_poses
from motion2robot.retarget.scale import Scale
from motion2robot.robot.poses import frame_poses
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion


def robot_points(motion: RobotMotion, robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per frame of ``motion``: (T, 22, 3) keypoint positions (m, world; rows of SMPL22 joints the
    robot does not track are NaN), (22,) bool mask of the tracked ones, and (T, 3) the torso body's
    up axis (the axis that points up at the nominal pose)."""
    if tuple(motion.joint_names) != tuple(robot.joint_names):
        raise UserError(f"the robot motion is for joints {motion.joint_names[:3]}..., not {robot.name}'s; "
                        f"project with the robot it was made for ({motion.robot})")
    data = robot.new_data()
    up_local = data.xmat[robot.torso_body].reshape(3, 3).T @ np.array([0.0, 0.0, 1.0])
    idx = np.array([KP[k] for k in robot.keypoints])
    mapped = np.zeros(len(SMPL22), dtype=bool)
    mapped[idx] = True
    pts = np.full((motion.num_frames, len(SMPL22), 3), np.nan)
    poses = frame_poses(robot.model, motion.qpos, robot.keypoint_sites, [robot.torso_body])
    pts[:, idx] = poses.sites
    up = np.stack([R.reshape(3, 3) @ up_local for R in poses.xmat[:, 0]]) if motion.num_frames else np.empty((0, 3))
    return pts, mapped, up


def _scale_of(motion: RobotMotion) -> Scale:
    s = motion.meta.get("scale")
    if not (isinstance(s, Mapping) and all(isinstance(s.get(k), (int, float)) for k in ("legs", "arms", "height"))):
        raise UserError("the robot motion has no meta['scale'] (legs, arms, height): project needs the scale "
                        "the retargeter applied; retarget it with this version of motion2robot")
    return Scale(float(s["legs"]), float(s["arms"]), float(s["height"]))


def project_motion(motion: RobotMotion, robot: Robot, original: HumanMotion) -> HumanMotion:
    """``human'``: the robot motion mapped back onto the human skeleton at ``original``'s scale,
    tempo, frame count and rate (see the module text). ``motion`` must have been retargeted from
    ``original`` (its meta carries the scale, the tempo and the contacts used)."""
    tempo = float(motion.meta.get("tempo") or 1.0)
    u = robot_frames(original.num_frames, original.fps, motion.fps, tempo, motion.num_frames)
    # the robot's poses at the human's frames (joint space): each frame of human' one the robot takes
    pts, mapped, up = robot_points(motion.with_(qpos=sample_poses(motion.qpos, u, robot.lower, robot.upper)), robot)
    if not mapped[KP["pelvis"]]:
        raise UserError(f"{robot.name} has no pelvis keypoint: the projection rebuilds the skeleton from the pelvis")
    scale = _scale_of(motion)
    orig = np.asarray(original.positions)
    first = unscale(pts, mapped, scale, orig)  # the mapped joints do not depend on the fill's values
    out = unscale(pts, mapped, scale, fill_torso(orig, first, up, mapped))
    labels = motion.meta.get("schedule")  # a walking pattern's: the labels that schedule it again
    if np.shape(labels) != (motion.num_frames, 2):
        labels = motion.meta.get("contacts")
    contacts = None
    if labels is not None and np.shape(labels) == (motion.num_frames, 2):
        contacts = np.asarray(labels, dtype=bool)[np.clip(np.rint(u).astype(int), 0, motion.num_frames - 1)]
    meta = {"projected": {"robot": motion.robot, "tempo": tempo, "fallback": motion.meta.get("fallback"),
                          "executable": motion.meta.get("executable"),
                          "filled": [n for n, m in zip(SMPL22, mapped) if not m]}}
    return original.with_(positions=out, contacts=contacts, meta=meta)

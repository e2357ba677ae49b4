"""The pure maths of the projection (see :mod:`motion2robot.projection`): time map, inverse of the
per-limb scale, torso frames and the fill of joints the robot has no keypoint for, distances,
the canonical frame's inverse. Positions in metres, z up, (T, 22, 3) SMPL22 arrays."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from motion2robot.motion.human import KP, SMPL22, SMPL22_PARENTS
from motion2robot.retarget.scale import BONE_GROUP, Scale

#: The torso joints (filled rigidly in the torso frame when the robot has no keypoint for them).
TORSO = ("pelvis", "spine1", "spine2", "spine3", "neck", "left_collar", "right_collar")

def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def robot_frames(n_human: int, human_fps: float, robot_fps: float, tempo: float, n_robot: int) -> np.ndarray:
    """(n_human,) fractional robot frame index of each human frame: human time i / f_h played
    ``tempo`` times slower at the robot's rate (clamped to the robot motion's last frame)."""
    return np.minimum(np.arange(n_human) * (tempo * robot_fps / human_fps), n_robot - 1)


def torso_rotations(up: np.ndarray, left: np.ndarray) -> np.ndarray:
    """(T, 3, 3) rotations whose columns are forward, left, up: ``up`` (T, 3) kept, ``left``
    (T, 3) made orthogonal to it, forward = left x up."""
    z = _unit(up)
    y = _unit(left - np.sum(left * z, axis=-1, keepdims=True) * z)
    x = np.cross(y, z)
    return np.stack([x, y, z], axis=-1)


def human_torso(positions: np.ndarray) -> np.ndarray:
    """(T, 3, 3) torso frames of (T, 22, 3) keypoints: up spine1 -> neck, left right -> left hip."""
    up = positions[:, KP["neck"]] - positions[:, KP["spine1"]]
    return torso_rotations(up, positions[:, KP["left_hip"]] - positions[:, KP["right_hip"]])


def unscale(points: np.ndarray, mapped: np.ndarray, scale: Scale, fill: np.ndarray) -> np.ndarray:
    """Invert :func:`~motion2robot.retarget.scale.scaled_keypoints` on the mapped joints.

    points: (T, 22, 3) robot-sized keypoints (rows of unmapped joints ignored); mapped: (22,) bool;
    fill: (T, 22, 3) human-sized positions for the unmapped joints. Returns (T, 22, 3) human-sized
    positions whose scaled keypoints equal ``points`` on every mapped joint (the pelvis must be
    mapped). Bones are rebuilt from the pelvis outwards, so an unmapped joint between two mapped
    ones (a collar between the spine and a shoulder) moves its child's bone, not its target."""
    ratio = {"legs": scale.legs, "arms": scale.arms, "height": scale.height}
    out = np.empty_like(points, dtype=np.float64)
    scaled = np.empty_like(out)  # the scaled position of each joint as rebuilt so far
    out[:, 0] = points[:, 0] / scale.legs
    scaled[:, 0] = points[:, 0]
    for j in range(1, len(SMPL22)):
        p, r = SMPL22_PARENTS[j], ratio[BONE_GROUP[SMPL22[j]]]
        if mapped[j]:
            out[:, j] = out[:, p] + (points[:, j] - scaled[:, p]) / r
            scaled[:, j] = points[:, j]
        else:
            out[:, j] = fill[:, j]
            scaled[:, j] = scaled[:, p] + r * (fill[:, j] - out[:, p])
    return out


def fill_torso(original: np.ndarray, projected: np.ndarray, robot_up: np.ndarray, mapped: np.ndarray) -> np.ndarray:
    """(T, 22, 3) positions for the joints the robot has no keypoint for (see the module text,
    step 3): each unmapped joint keeps its offset from the neck (torso joints) or from its parent
    (others) in the original's torso frame, placed in the frame whose up is ``robot_up`` (T, 3)
    and whose left is the projected hips'. ``projected`` must hold the mapped joints (the neck and
    hips at least); rows of unmapped joints are read only as parents, after being filled."""
    R = human_torso(original)
    Rp = torso_rotations(robot_up, projected[:, KP["left_hip"]] - projected[:, KP["right_hip"]])
    turn = np.einsum("tij,tkj->tik", Rp, R)  # Rp R^T: original torso frame -> projected one
    out = projected.copy()
    neck = KP["neck"]
    for j in range(1, len(SMPL22)):
        if mapped[j]:
            continue
        anchor = neck if SMPL22[j] in TORSO and mapped[neck] else SMPL22_PARENTS[j]
        out[:, j] = out[:, anchor] + np.einsum("tij,tj->ti", turn, original[:, j] - original[:, anchor])
    return out


def bone_lengths(positions: np.ndarray) -> np.ndarray:
    """(T, 22) length (m) of the bone from each SMPL22 joint's parent to the joint (0 for the
    pelvis) in (T, 22, 3) ``positions``."""
    P = np.asarray(positions, dtype=np.float64)
    out = np.zeros(P.shape[:2])
    out[:, 1:] = np.linalg.norm(P[:, 1:] - P[:, list(SMPL22_PARENTS[1:])], axis=-1)
    return out


def bone_drift(positions: np.ndarray, reference: np.ndarray) -> float:
    """The largest relative change (0 = none) of a bone's length, over frames and bones, between
    (T, 22, 3) ``positions`` and ``reference`` (bones of zero reference length left out)."""
    a, b = bone_lengths(positions)[:, 1:], bone_lengths(reference)[:, 1:]
    ok = b > 1e-9
    return float(np.max(np.abs(a[ok] / b[ok] - 1.0), initial=0.0))


def keep_bones(positions: np.ndarray, reference: np.ndarray, slack: float = 0.0) -> np.ndarray:
    """(T, 22, 3) ``positions`` rebuilt from the pelvis outwards with each bone's direction as it
    is and its length within ``slack`` (a fraction) of the same bone's in (T, 22, 3)
    ``reference``, frame by frame (a bone shrunk to a point takes the reference's direction): the
    skeleton nearest the motion's bone directions, which are what the retargeter's targets are
    built from (:func:`~motion2robot.retarget.scale.scaled_keypoints`)."""
    P = np.asarray(positions, dtype=np.float64)
    R = np.asarray(reference, dtype=np.float64)
    out = np.empty_like(P)
    out[:, 0] = P[:, 0]
    for j in range(1, len(SMPL22)):
        p = SMPL22_PARENTS[j]
        bone, ref = P[:, j] - P[:, p], R[:, j] - R[:, p]
        norm = np.linalg.norm(bone, axis=-1, keepdims=True)
        ref_len = np.linalg.norm(ref, axis=-1, keepdims=True)
        point = norm <= 1e-9 * np.maximum(ref_len, 1e-9)
        bone, norm = np.where(point, ref, bone), np.where(point, ref_len, norm)
        length = np.clip(norm, ref_len * (1.0 - slack), ref_len * (1.0 + slack))
        out[:, j] = out[:, p] + bone * (length / np.maximum(norm, 1e-300))
    return out


def joint_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(T, 22) Euclidean distance (m) between two (T, 22, 3) keypoint arrays."""
    return np.linalg.norm(np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64), axis=-1)


def from_canonical(transform: Mapping[str, Any] | None, points: np.ndarray) -> np.ndarray:
    """Canonical points (..., 3) -> the file's own axes and units, inverting a clip's
    ``meta["canonical_transform"]`` (p_canonical = matrix @ p + offset); unchanged without one."""
    if not transform:
        return np.asarray(points, dtype=np.float64).copy()
    a = np.asarray(transform["matrix"], dtype=np.float64)
    offset = np.asarray(transform["offset"], dtype=np.float64)
    return (np.asarray(points, dtype=np.float64) - offset) @ np.linalg.inv(a).T

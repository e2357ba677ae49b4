"""A test-side encoder: joint positions (T, 22, 3), z up -> MotionFix/OmniME 207-d raw features.

Written from the facts sheet's definitions, independently of the decoder: the pelvis frame R_i is
built from the joints (up = spine3 - pelvis, left = left_hip - right_hip), its heading is the yaw of
its x axis, the translation is the pelvis joint. Joints carry no twist, so body_pose (unused for
positions) is written as identity rotations.
"""

from __future__ import annotations

import numpy as np


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def pelvis_frames(joints: np.ndarray) -> np.ndarray:
    """(T, 22, 3) -> (T, 3, 3) rotation matrices (columns: forward, left, up)."""
    up = _unit(joints[:, 9] - joints[:, 0])
    left = joints[:, 1] - joints[:, 2]
    left = _unit(left - np.sum(left * up, axis=-1, keepdims=True) * up)
    fwd = np.cross(left, up)
    return np.stack([fwd, left, up], axis=-1)


def _rz(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    out = np.zeros((len(a), 3, 3))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1], out[:, 2, 2] = c, -s, s, c, 1.0
    return out


def encode(joints: np.ndarray) -> np.ndarray:
    """(T, 22, 3) metres, z up -> (T, 207) raw features."""
    j = np.asarray(joints, dtype=np.float64)
    t = j.shape[0]
    r = pelvis_frames(j)
    rz = _rz(np.arctan2(r[:, 1, 0], r[:, 0, 0]))
    rxy = np.transpose(rz, (0, 2, 1)) @ r
    d = np.empty((t, 3, 3))
    d[0] = np.eye(3)
    d[1:] = np.transpose(rz[:-1], (0, 2, 1)) @ rz[1:]
    trans = j[:, 0]
    v = np.zeros((t, 3))
    v[1:] = np.einsum("tji,tj->ti", r[:-1], trans[1:] - trans[:-1])  # R_{i-1}^T (t_i - t_{i-1})
    rel = np.einsum("tji,tkj->tki", rz, j - j[:, :1])  # Rz_i^T (p - pelvis_i)
    pose = np.tile(np.eye(3)[:2].reshape(6), (t, 21))
    return np.concatenate([v, rxy[:, :2].reshape(t, 6), d[:, :2].reshape(t, 6), pose, rel.reshape(t, 66)], axis=1)

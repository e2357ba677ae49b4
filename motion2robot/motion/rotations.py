"""Rotation matrices from the parameterisations motion models write, vectorised over leading axes.

- "6D" (the pytorch3d convention used by MotionFix/OmniME): the first two ROWS of the matrix;
  the matrix is recovered by Gram-Schmidt on those rows and their cross product as third row.
- axis-angle (SMPL / AMASS / AIST++ poses): Rodrigues' formula.
- yaw: the rotation about +z of a matrix's x axis, and the pure z rotation it names.
"""

from __future__ import annotations

import numpy as np


def matrix_from_6d(d6: np.ndarray) -> np.ndarray:
    """(..., 6) -> (..., 3, 3): rows r1 = a/|a|, r2 = b minus its r1 part, normalised, r3 = r1 x r2."""
    d6 = np.asarray(d6, dtype=np.float64)
    a, b = d6[..., :3], d6[..., 3:6]
    with np.errstate(invalid="ignore", divide="ignore"):  # a zero row gives NaN, which the readers refuse
        r1 = a / np.linalg.norm(a, axis=-1, keepdims=True)
        b = b - np.sum(r1 * b, axis=-1, keepdims=True) * r1
        r2 = b / np.linalg.norm(b, axis=-1, keepdims=True)
    return np.stack([r1, r2, np.cross(r1, r2)], axis=-2)


def matrix_to_6d(r: np.ndarray) -> np.ndarray:
    """(..., 3, 3) -> (..., 6): the first two rows."""
    r = np.asarray(r, dtype=np.float64)
    return r[..., :2, :].reshape(*r.shape[:-2], 6)


def matrix_from_axis_angle(aa: np.ndarray) -> np.ndarray:
    """(..., 3) axis * angle (radians) -> (..., 3, 3), Rodrigues' formula (exact at angle 0)."""
    aa = np.asarray(aa, dtype=np.float64)
    angle = np.linalg.norm(aa, axis=-1)
    k = aa / np.where(angle > 1e-12, angle, 1.0)[..., None]
    kx, ky, kz = k[..., 0], k[..., 1], k[..., 2]
    zero = np.zeros_like(kx)
    cross = np.stack([np.stack([zero, -kz, ky], -1), np.stack([kz, zero, -kx], -1),
                      np.stack([-ky, kx, zero], -1)], -2)
    s, c = np.sin(angle)[..., None, None], np.cos(angle)[..., None, None]
    return np.eye(3) + s * cross + (1.0 - c) * (cross @ cross)


def yaw_of(r: np.ndarray) -> np.ndarray:
    """(..., 3, 3) -> (...) heading angle of the matrix's x axis about +z (radians)."""
    return np.arctan2(r[..., 1, 0], r[..., 0, 0])


def rot_z(angle: np.ndarray) -> np.ndarray:
    """(...) angles -> (..., 3, 3) rotations about +z."""
    a = np.asarray(angle, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    out = np.zeros((*a.shape, 3, 3))
    out[..., 0, 0], out[..., 0, 1], out[..., 1, 0], out[..., 1, 1], out[..., 2, 2] = c, -s, s, c, 1.0
    return out

"""HumanML3D / KIT-ML feature vectors -> joint positions (vectorised over frames and clips).

Layout per frame for J joints (J = 22: D = 263, HumanML3D; J = 21: D = 251, KIT-ML):
root yaw velocity (1), root planar velocity x, z in the heading frame (2), root height y (1),
"ric" positions of joints 1..J-1 in the heading frame ((J-1) x 3), 6D rotations ((J-1) x 6),
joint velocities (J x 3), foot contacts (4: left ankle, left toe, right ankle, right toe).
Axes are the data set's: y up, metres. See docs/facts: the integrated heading h is a HALF
angle; the world rotation of frame t is R_y(-2 h_t).
"""

from __future__ import annotations

import numpy as np

_CHUNK_FRAMES = 8192  # frames per block when decoding a large batch (keeps temporaries in cache)

#: Joint count by feature dimension.
JOINTS_BY_DIM = {263: 22, 251: 21}


def feature_dim(joints: int) -> int:
    return 4 + (joints - 1) * 9 + joints * 3 + 4


def contact_slice(dim: int) -> slice:
    """The four foot contact channels (left ankle, left toe, right ankle, right toe)."""
    return slice(dim - 4, dim)


def decode_positions(feat: np.ndarray) -> np.ndarray:
    """(..., T, D) raw (denormalised) features -> (..., T, J, 3) joint positions, y up, metres.

    h_t = sum_{k<t} feat[k, 0]; world = R_y(-2 h_t) @ local; the root's ground position is the
    running sum of feat[t-1, 1:3] rotated by R_y(-2 h_t); root height = feat[t, 3].
    """
    feat = np.asarray(feat)
    if feat.ndim >= 3 and feat.shape[0] > 1 and feat[..., 0].size > _CHUNK_FRAMES:
        step = max(1, _CHUNK_FRAMES // max(1, feat[0, ..., 0].size))  # cache-sized chunks of clips
        return np.concatenate([decode_positions(feat[i:i + step]) for i in range(0, feat.shape[0], step)])
    dim = feat.shape[-1]
    if dim not in JOINTS_BY_DIM:
        raise ValueError(f"feature dimension {dim} is not one of {sorted(JOINTS_BY_DIM)}")
    j = JOINTS_BY_DIM[dim]
    lead = feat.shape[:-1]
    root = feat[..., :4].astype(np.float64)  # only the channels needed, in float64
    ric = feat[..., 4:4 + (j - 1) * 3].astype(np.float64).reshape(*lead, j - 1, 3)
    h = np.zeros(lead)
    np.cumsum(root[..., :-1, 0], axis=-1, out=h[..., 1:])
    h *= 2.0
    c, s = np.cos(h), np.sin(h)  # R_y(-2h) = [[c, 0, -s], [0, 1, 0], [s, 0, c]]
    vx = np.zeros(lead)
    vz = np.zeros(lead)
    vx[..., 1:] = root[..., :-1, 1]
    vz[..., 1:] = root[..., :-1, 2]
    root_x = np.cumsum(c * vx - s * vz, axis=-1)
    root_z = np.cumsum(s * vx + c * vz, axis=-1)
    out = np.empty((*lead, j, 3))
    cc, ss = c[..., None], s[..., None]
    rx, rz = ric[..., 0], ric[..., 2]
    out[..., 1:, 0] = cc * rx - ss * rz + root_x[..., None]
    out[..., 1:, 1] = ric[..., 1]
    out[..., 1:, 2] = ss * rx + cc * rz + root_z[..., None]
    out[..., 0, 0] = root_x
    out[..., 0, 1] = root[..., 3]
    out[..., 0, 2] = root_z
    return out


def decode_contacts(feat: np.ndarray) -> np.ndarray:
    """(..., T, D) raw features -> (..., T, 2) bool foot contacts [left, right]; a foot is in
    contact when its ankle or toe flag is set (> 0.5)."""
    f = np.asarray(feat)[..., contact_slice(feat.shape[-1])] > 0.5
    return np.stack([f[..., 0] | f[..., 1], f[..., 2] | f[..., 3]], axis=-1)


def looks_raw(feat: np.ndarray) -> bool:
    """True when the contact channels hold only 0/1 values (raw features); normalised features
    hold (flag - mean) / std instead."""
    c = np.asarray(feat)[..., contact_slice(feat.shape[-1])]
    return bool(np.all((np.abs(c) < 1e-6) | (np.abs(c - 1.0) < 1e-6)))

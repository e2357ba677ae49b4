"""The edited robot motion: the source's robot trajectory wherever a hinge's parts are unedited,
the edit's where they changed, and a smooth blend of bounded length in between.

Weights per frame and hinge: w = 1 (the source's value, exactly) at frames at least ``blend``
frames away from any frame where the hinge's parts changed, w = 0 (the edit's value) at changed
frames, and a smoothstep of the distance in between. The root (position and wxyz quaternion) is
driven by the "global" part; its orientation is blended by normalised linear interpolation.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np


def source_weights(changed: np.ndarray, blend: int) -> np.ndarray:
    """(T,) bool changed frames -> (T,) weight of the source in [0, 1] (1 beyond ``blend`` frames)."""
    t = changed.size
    if not changed.any():
        return np.ones(t)
    idx = np.flatnonzero(changed)
    frames = np.arange(t)
    pos = np.searchsorted(idx, frames)
    left = np.abs(frames - idx[np.clip(pos - 1, 0, idx.size - 1)])
    right = np.abs(idx[np.clip(pos, 0, idx.size - 1)] - frames)
    dist = np.minimum(left, right).astype(float)
    if blend <= 0:
        return (dist > 0).astype(float)
    u = np.clip(dist / blend, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def compose(q_source: np.ndarray, q_edit: np.ndarray, parts_changed: Mapping[str, np.ndarray],
            hinge_parts: Sequence[frozenset[str]], blend: int) -> tuple[np.ndarray, np.ndarray]:
    """(qpos (T, 7 + n), weights (T, n + 1): the source's share per hinge, root last)."""
    t = q_source.shape[0]
    out = q_edit.copy()
    weights = np.empty((t, len(hinge_parts) + 1))
    for h, parts in enumerate(hinge_parts):
        changed = np.any([parts_changed[p] for p in parts], axis=0)
        w = source_weights(changed, blend)
        weights[:, h] = w
        out[:, 7 + h] = w * q_source[:, 7 + h] + (1.0 - w) * q_edit[:, 7 + h]
    w = source_weights(parts_changed["global"], blend)
    weights[:, -1] = w
    out[:, :3] = w[:, None] * q_source[:, :3] + (1.0 - w[:, None]) * q_edit[:, :3]
    qs, qe = q_source[:, 3:7], q_edit[:, 3:7]
    qe = np.where(np.sum(qs * qe, axis=1, keepdims=True) < 0, -qe, qe)  # same hemisphere
    quat = w[:, None] * qs + (1.0 - w[:, None]) * qe
    out[:, 3:7] = quat / np.linalg.norm(quat, axis=1, keepdims=True)
    exact = w == 1.0
    out[exact, 3:7] = q_source[exact, 3:7]
    for h in range(len(hinge_parts)):
        keep = weights[:, h] == 1.0
        out[keep, 7 + h] = q_source[keep, 7 + h]
    return out, weights

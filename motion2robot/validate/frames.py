"""Frame-set helpers shared by the checks."""

from __future__ import annotations

import numpy as np

from motion2robot.util.ranges import runs


def keep_runs(mask: np.ndarray, min_run: int) -> np.ndarray:
    """``mask`` (T, ...) bool with runs (along axis 0) shorter than ``min_run`` frames cleared."""
    mask = np.asarray(mask, dtype=bool)
    if min_run <= 1 or not mask.any():
        return mask.copy()
    flat = mask.reshape(mask.shape[0], -1)
    out = np.zeros_like(flat)
    for c in np.flatnonzero(flat.any(axis=0)):
        for s, e in runs(np.flatnonzero(flat[:, c])):
            if e - s + 1 >= min_run:
                out[s:e + 1, c] = True
    return out.reshape(mask.shape)


def frame_list(mask: np.ndarray) -> list[int]:
    """Indices of frames where ``mask`` (T, ...) has any True, as plain ints."""
    mask = np.asarray(mask, dtype=bool)
    if mask.ndim > 1:
        mask = mask.reshape(mask.shape[0], -1).any(axis=1)
    return np.flatnonzero(mask).tolist()


def first_time(frames: list[int], fps: float) -> float | None:
    return round(frames[0] / fps, 3) if frames else None

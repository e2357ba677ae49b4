"""Input checks shared by the readers: one-line :class:`InputFileError` messages.

Every message reads "<path>: <problem>; <fix>" so the CLI can print it as is.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2robot.errors import InputFileError
from motion2robot.util.ranges import frame_ranges


def fail(path: str | Path, problem: str, fix: str) -> InputFileError:
    """The error to raise for a bad input file (caller does ``raise fail(...)``)."""
    return InputFileError(f"{path}: {problem}; {fix}")


def check_frames(path: str | Path, positions: np.ndarray, what: str = "positions") -> None:
    """Refuse non-finite frames (naming them) and clips shorter than 2 frames.

    positions: (T, ...) array, any trailing shape.
    """
    t = positions.shape[0]
    if t < 2:
        raise fail(path, f"has {t} frame{'s' if t != 1 else ''}, a motion needs at least 2",
                   "export a longer clip")
    if np.isfinite(positions).all():  # the common case: one pass, no per-frame reduction
        return
    bad = ~np.isfinite(positions.reshape(t, -1)).all(axis=1)
    if bad.any():
        idx = np.flatnonzero(bad)
        raise fail(path, f"{what} hold NaN/inf values in {idx.size} of {t} frames "
                         f"(frames {frame_ranges(idx)})",
                   "fix or trim those frames in the source (e.g. regenerate the clip)")

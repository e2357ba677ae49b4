"""Input checks shared by the readers: one-line :class:`InputFileError` messages.

Every message reads "<path>: <problem>; <fix>" so the CLI can print it as is.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from motion2robot.errors import InputFileError, InputWarning
from motion2robot.util.ranges import frame_ranges


def fail(path: str | Path, problem: str, fix: str) -> InputFileError:
    """The error to raise for a bad input file (caller does ``raise fail(...)``)."""
    return InputFileError(f"{path}: {problem}; {fix}")


def trailing_zero_frames(sample: np.ndarray) -> int:
    """Number of frames at the end of (T, ...) ``sample`` whose values are all exactly zero (the
    padding generators put after a shorter sample: no body has every joint at the origin, no
    feature vector is exactly zero)."""
    flat = np.asarray(sample).reshape(len(sample), -1)
    if len(flat) == 0 or np.any(flat[-1] != 0):  # the common case: the last frame alone decides
        return 0
    nonzero = np.flatnonzero(np.any(flat != 0, axis=1))
    return len(flat) if len(nonzero) == 0 else len(flat) - 1 - int(nonzero[-1])


#: What to do with a padded sample (the same sentence for every reader).
PADDING_FIX = ("cut each sample at its length; for a padded batch give the lengths: MDM's results.npy "
               "(motion, text, lengths), an .npz with joints=(N, T, 22, 3), lengths=(N,) and fps, or "
               "lengths= in motion2robot.api")


def check_frames(path: str | Path, positions: np.ndarray, what: str = "positions") -> None:
    """Refuse non-finite frames (naming them), clips shorter than 2 frames and trailing all-zero
    frames (a padded sample read without its length).

    positions: (T, ...) array, any trailing shape.
    """
    t = positions.shape[0]
    if t < 2:
        raise fail(path, f"has {t} frame{'s' if t != 1 else ''}, a motion needs at least 2",
                   "export a longer clip")
    if np.isfinite(positions).all():  # the common case: one pass, no per-frame reduction
        pad = trailing_zero_frames(positions)
        if pad == t:
            raise fail(path, f"{what} are all zero in every one of its {t} frames (padding, not a motion)", PADDING_FIX)
        if pad:
            raise fail(path, f"{what} end with {pad} all-zero frames (frames {t - pad}-{t - 1} of {t}): padding "
                             "after a shorter sample, not motion", PADDING_FIX)
        return
    bad = ~np.isfinite(positions.reshape(t, -1)).all(axis=1)
    if bad.any():
        idx = np.flatnonzero(bad)
        raise fail(path, f"{what} hold NaN/inf values in {idx.size} of {t} frames "
                         f"(frames {frame_ranges(idx)})",
                   "fix or trim those frames in the source (e.g. regenerate the clip)")


#: A raw coordinate farther than this from the origin (in the file's own units; 1,000 km in metres,
#: 1 km in millimetres) is no position of a body: the solve and the unit detection would overflow.
MAX_COORDINATE = 1e6
#: Frame rates a motion may declare (frames per second).
FPS_RANGE = (0.1, 10000.0)


def check_fps(path: str | Path, fps: Any, source: str = "the file's frame rate") -> float:
    """``fps`` as a float if it is a plausible frame rate, else InputFileError naming ``source``."""
    try:
        v = float(fps) if not isinstance(fps, (bool, np.bool_)) else math.nan
    except (TypeError, ValueError):
        v = math.nan
    lo, hi = FPS_RANGE
    if not (math.isfinite(v) and lo <= v <= hi):
        raise fail(path, f"{source} is {fps!r}, not a frame rate ({lo:g} to {hi:g} fps)",
                   "fix the file's frame rate or pass --source-fps")
    return v


def numeric_positions(path: str | Path, values: Any, what: str = "positions") -> np.ndarray:
    """``values`` as a float64 array, refusing text, objects, booleans and complex numbers with
    non-zero imaginary parts (zero imaginary parts are dropped)."""
    arr = np.asarray(values)
    if arr.dtype.kind == "c":
        imag = np.abs(arr.imag)
        if np.any(imag > 0):
            raise fail(path, f"{what} are complex numbers (imaginary parts up to {float(np.nanmax(imag)):.3g})",
                       "save real-valued coordinates")
        warnings.warn(InputWarning(f"{path}: {what} are stored as complex numbers (all imaginary parts 0); "
                                   "reading the real parts"), stacklevel=3)
        arr = arr.real
    if arr.dtype.kind not in "fiu":
        raise fail(path, f"{what} hold {arr.dtype} values, not numbers", "save a float array of coordinates")
    return np.asarray(arr, dtype=np.float64)


def check_magnitude(path: str | Path, positions: np.ndarray, names: tuple[str, ...] | None = None,
                    limit: float = MAX_COORDINATE) -> None:
    """Refuse (T, J, 3) coordinates beyond ``limit`` (file units), naming the first frame and joint."""
    big = np.abs(positions) > limit
    if not big.any():
        return
    t, j = (int(x) for x in np.argwhere(big.reshape(positions.shape[0], -1, positions.shape[-1]))[0][:2])
    v = float(np.abs(positions.reshape(positions.shape[0], -1, positions.shape[-1])[t, j]).max())
    joint = names[j] if names is not None and j < len(names) else f"joint {j}"
    n = int(big.reshape(positions.shape[0], -1).any(axis=1).sum())
    raise fail(path, f"frame {t}, {joint} is {v:.3g} units from the origin (and {n} frame(s) in all beyond "
                     f"{limit:g}), which is no position of a body", "fix or trim those frames in the source")

"""Batches of motions as generators produce them -> canonical clips, for the in-process API.

Accepted: a numpy array or a torch-like tensor (anything with ``detach``/``cpu``/``numpy``; torch is
never imported) of shape (B, T, 22, 3) joint positions (HumanML3D: metres, y up), MDM's
(B, 22, 3, T), or (B, T, 263) HumanML3D features (raw, or normalised with ``mean``/``std``); a single
sample without the batch axis; or a list of such samples of different lengths, or of
:class:`~motion2robot.motion.human.HumanMotion` clips. ``lengths`` (B integers) gives each padded
sample's valid frames. Problems with the batch as a whole raise
:class:`~motion2robot.errors.MotionBatchError`; a sample with NaN/inf in its valid frames is not
raised but returned as an error message, so the other samples are still scored.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from motion2robot.errors import MotionBatchError, UserError
from motion2robot.motion.checks import trailing_zero_frames
from motion2robot.motion.human import HumanMotion
from motion2robot.motion.tensors import from_tensor, to_numpy
from motion2robot.util.ranges import frame_ranges

#: Last-axis sizes of feature layouts -> from_tensor layout.
FEATURES = {263: "humanml3d_vecs", 207: "motionfix_207"}
NAME = "<tensor>"


def _layout(shape: tuple[int, ...]) -> tuple[str, int]:
    """(layout, number of axes of one sample) of a batch or sample shape."""
    if len(shape) >= 2 and shape[-1] in FEATURES:
        return FEATURES[shape[-1]], 2
    if len(shape) >= 3 and shape[-2:] == (22, 3):
        return "humanml3d_joints", 3
    if len(shape) == 4 and shape[1:3] == (22, 3):
        return "mdm", 3
    raise MotionBatchError(f"motions of shape {shape}: expected (B, T, 22, 3) joints, (B, 22, 3, T) (MDM), or "
                           "(B, T, 263) HumanML3D features (a single sample without B also works)")


def _lengths(lengths: Any, batch: int, frames: int) -> np.ndarray:
    arr = to_numpy(lengths)
    if arr.ndim != 1 or len(arr) != batch:
        raise MotionBatchError(f"lengths has shape {arr.shape}; give one integer per sample ({batch} values)")
    if arr.dtype.kind not in "iu" and not (arr.dtype.kind == "f" and np.all(arr == np.round(arr))):
        raise MotionBatchError(f"lengths must be whole numbers of frames, got {arr[:4].tolist()}...")
    arr = arr.astype(int)
    bad = np.flatnonzero((arr < 1) | (arr > frames))
    if len(bad):
        raise MotionBatchError(f"lengths[{int(bad[0])}] = {int(arr[bad[0]])} is outside 1..{frames} (the batch has "
                               f"{frames} frames per sample)")
    return arr


def _split(motions: Any, lengths: Any) -> tuple[list[np.ndarray], str]:
    """The samples as (T_i, ...) arrays cut to their lengths, and their layout."""
    if isinstance(motions, (list, tuple)):
        if lengths is not None:
            raise MotionBatchError("lengths is for a padded batch array; a list of samples carries its own lengths")
        if not motions:
            raise MotionBatchError("no motions given (an empty list)")
        samples = [to_numpy(m) for m in motions]
        layouts = {_layout(s.shape) for s in samples}
        if len(layouts) > 1 or next(iter(layouts))[1] != samples[0].ndim:
            raise MotionBatchError(f"a list of samples must hold single samples of one layout; got shapes "
                                   f"{sorted({s.shape for s in samples})[:3]}")
        return samples, next(iter(layouts))[0]
    arr = to_numpy(motions)
    layout, axes = _layout(arr.shape)
    if arr.ndim == axes:
        arr = arr[None]
    if layout == "mdm":
        arr, layout = np.moveaxis(arr, 3, 1), "humanml3d_joints"
    if not np.issubdtype(arr.dtype, np.number):
        raise MotionBatchError(f"motions have dtype {arr.dtype}; give numbers")
    batch, frames = arr.shape[:2]
    if lengths is None:
        padded = [(b, trailing_zero_frames(arr[b])) for b in range(batch)]
        padded = [(b, n) for b, n in padded if n]
        if padded:
            b, n = padded[0]
            raise MotionBatchError(f"sample {b} ends with {n} all-zero frames (padding), and {len(padded)} of {batch} "
                                   "samples are padded; pass lengths= (the valid frames of each sample)")
        return list(arr), layout
    return [arr[b, :n] for b, n in enumerate(_lengths(lengths, batch, frames))], layout


def to_clips(motions: Any, *, lengths: Any = None, fps: float | None = None, mean: Any = None,
             std: Any = None) -> list[HumanMotion | str]:
    """One canonical clip per sample, or a one-line error message for a sample that cannot be
    read (NaN/inf, a reader's complaint). See the module text."""
    if isinstance(motions, (list, tuple)) and motions and all(isinstance(m, HumanMotion) for m in motions):
        if lengths is not None:
            raise MotionBatchError("lengths is for a padded batch array, not a list of HumanMotion clips")
        return list(motions)
    samples, layout = _split(motions, lengths)
    out: list[HumanMotion | str] = []
    for b, s in enumerate(samples):
        finite = np.isfinite(s.reshape(len(s), -1)).all(axis=1)
        if not finite.all():
            out.append(f"input: sample {b} has NaN/inf in frames {frame_ranges(np.flatnonzero(~finite))}; "
                       "fix or drop that sample")
            continue
        try:
            clip = from_tensor(s, layout, fps=fps, mean=mean, std=std, name=f"{NAME}[{b}]")[0]
        except UserError as err:
            out.append(f"read: {err}")
            continue
        out.append(clip.with_(meta={"clip": b}))
    return out


"""One motion given in-process (a HumanMotion, a numpy array, a tensor) as a canonical
HumanMotion, refusing batches, wrong shapes and non-finite values with one clear exception."""

from __future__ import annotations

from typing import Any

import numpy as np

from motion2robot.errors import UserError
from motion2robot.motion.human import HumanMotion


#: Shape of one sample (after the frame axis) per layout of :mod:`~motion2robot.motion.tensors`.
SAMPLE_SHAPE: dict[str, tuple[int, ...]] = {
    "humanml3d_joints": (22, 3), "humanml3d_vecs": (263,), "motionfix_207": (207,),
}


class MotionArrayError(UserError, ValueError):
    """An in-process motion (numpy array or tensor) has the wrong shape or non-finite values."""


def as_human(motion: Any, *, layout: str = "humanml3d_joints", fps: float | None = None,
             mean: Any = None, std: Any = None) -> HumanMotion:
    """One motion as a canonical HumanMotion: a HumanMotion as it is, or an array / tensor (torch
    duck-typed, never imported) of one sample in a layout of :mod:`~motion2robot.motion.tensors`
    ((T, 22, 3) joints, (T, 263) features, ...). MotionArrayError for batches, wrong shapes and
    non-finite values."""
    if isinstance(motion, HumanMotion):
        arr = np.asarray(motion.positions)
    else:
        from motion2robot.motion.tensors import LAYOUTS, to_numpy

        if layout not in LAYOUTS:
            raise MotionArrayError(f"project: unknown layout {layout!r}; use one of {', '.join(LAYOUTS)}")
        arr = to_numpy(motion)
        tail = SAMPLE_SHAPE[layout]
        want = "(T, " + ", ".join(str(n) for n in tail) + ")"
        single = arr.ndim == len(tail) + 1 and tuple(arr.shape[1:]) == tail
        if not single or arr.shape[0] < 2:
            batch = arr.ndim == len(tail) + 2 and tuple(arr.shape[2:]) == tail
            hint = ("project one sample at a time (loop over the batch, cut each at its length)" if batch
                    else f"give one motion of shape {want} with at least 2 frames")
            raise MotionArrayError(f"project: the motion has shape {tuple(arr.shape)}, expected {want} for layout "
                                   f"{layout!r}; {hint}")
        if arr.dtype.kind not in "fiu":
            raise MotionArrayError(f"project: the motion holds {arr.dtype} values, not numbers; give a float array")
    bad = ~np.isfinite(np.asarray(arr, dtype=np.float64))
    if bad.any():
        frames = np.unique(np.argwhere(bad)[:, 0])
        raise MotionArrayError(f"project: the motion has NaN/inf values in {len(frames)} frame(s) (first: frame "
                               f"{int(frames[0])}); fix or drop those frames before projecting")
    if isinstance(motion, HumanMotion):
        return motion
    from motion2robot.motion.tensors import from_tensor

    return from_tensor(arr, layout, fps=fps, mean=mean, std=std, name="<array>")[0]

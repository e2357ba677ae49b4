"""Torch tensors in-process and ``.pt`` files. torch is imported only inside these functions."""

from __future__ import annotations

import pickle
import re
from pathlib import Path
from typing import Any

import numpy as np

from motion2robot.errors import InputFileError
from motion2robot.motion.checks import fail
from motion2robot.motion.human import HumanMotion
from motion2robot.motion.options import ReadOptions

LAYOUTS = ("humanml3d_joints", "humanml3d_vecs", "motionfix_207")
_TORCH_HINT = "pip install motion2robot[torch]"


def to_numpy(t: Any) -> np.ndarray:
    """A torch tensor (any device, with or without grad) or array-like -> numpy array."""
    if hasattr(t, "detach"):
        t = t.detach()
    if hasattr(t, "cpu"):
        t = t.cpu()
    if hasattr(t, "numpy"):
        try:
            return np.asarray(t.numpy())
        except TypeError:  # a dtype numpy lacks (torch's bfloat16): widen to float32 first
            if not hasattr(t, "float"):
                raise
            return np.asarray(t.float().numpy())
    return np.asarray(t)


def from_tensor(t: Any, layout: str = "humanml3d_joints", *, fps: float | None = None,
                mean: Any = None, std: Any = None, name: str = "<tensor>") -> list[HumanMotion]:
    """Tensor -> canonical clips. layout "humanml3d_joints": (T, 22, 3), (N, T, 22, 3) or MDM's
    (N, 22, 3, T); "humanml3d_vecs": (T, 263) or (N, T, 263), raw or normalised with mean/std
    (arrays or tensors of 263 values); "motionfix_207": (T, 207) or (N, T, 207) MotionFix/OmniME
    features, z up, 30 fps, raw or normalised with mean/std (207 values each) or ``mean`` set to the
    model's statistics dict."""
    from motion2robot.motion import read_arrays as R

    arr = to_numpy(t)
    path = Path(name)
    opts = ReadOptions(fps=fps)
    if layout == "humanml3d_joints":
        if arr.ndim == 4 and arr.shape[1] == 22 and arr.shape[2] == 3:
            return R.read_mdm_array(path, arr, opts)
        return R.read_joints(path, arr, opts)
    if layout == "humanml3d_vecs":
        if mean is not None and std is not None:
            m, s = to_numpy(mean).astype(np.float64), to_numpy(std).astype(np.float64)
            arr = arr * s + m
        return R.read_features(path, arr, opts)
    if layout == "motionfix_207":
        from motion2robot.motion.motionfix import features_to_clips, stats_arrays

        stats = None
        if isinstance(mean, dict):
            stats = stats_arrays(path, mean)
        elif mean is not None and std is not None:
            stats = stats_arrays(path, {"mean": to_numpy(mean), "std": to_numpy(std)})
        return features_to_clips(path, arr, opts, stats, "the given mean/std")
    raise InputFileError(f"{name}: unknown layout {layout!r}; use one of {', '.join(LAYOUTS)}")


def read_pt(path: Path, opts: ReadOptions) -> list[HumanMotion]:
    """A ``.pt`` file holding one tensor (or a dict with 'motion'/'joints'/'positions'),
    loaded with ``torch.load(weights_only=True)`` (no code execution). Layout from the shape."""
    try:
        import torch
    except ImportError:
        raise fail(path, "is a torch .pt file but torch is not installed", _TORCH_HINT) from None
    try:
        obj = torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as err:  # weights_only refused a Python object: never run it
        found = re.search(r"unsupported GLOBAL (\S+)", str(err))
        what = f" ({found.group(1).rstrip('.,')})" if found else ""
        raise fail(path, f"holds Python objects{what} beside tensors, which are not loaded (no code from a "
                   "file is run)", "save the motion tensor itself: torch.save(tensor, path)") from None
    except Exception as err:  # torch raises many types for bad files
        raise fail(path, f"could not be loaded by torch ({type(err).__name__}: {err})",
                   "save the tensor with torch.save") from None
    if isinstance(obj, dict):
        key = next((k for k in ("motion", "joints", "positions") if k in obj), None)
        if key is None:
            raise fail(path, f"holds a dict without 'motion'/'joints'/'positions' (keys {sorted(obj)})",
                       "save the motion tensor itself")
        obj = obj[key]
    arr = to_numpy(obj)
    from motion2robot.motion import read_arrays as R

    if arr.shape[-1] in (263, 251):
        return R.read_features(path, arr, opts)
    if arr.ndim == 4 and arr.shape[1] == 22 and arr.shape[2] == 3:
        return R.read_mdm_array(path, arr, opts)
    return R.read_joints(path, arr, opts)

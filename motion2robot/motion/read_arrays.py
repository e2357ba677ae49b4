"""Readers for numpy-held motion: HumanML3D joints and feature vectors, MDM results, .npz.

All return canonical :class:`HumanMotion` clips (via :func:`canonicalize`). HumanML3D-space
data (joints, features, MDM) is y up, metres, 20 fps by definition of the data set; the
units are still sanity-checked from the subject's size.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from motion2robot.motion import features as F
from motion2robot.motion.canonical import canonicalize
from motion2robot.motion.checks import check_fps, check_frames, fail
from motion2robot.motion.human import HumanMotion
from motion2robot.motion.options import ReadOptions
from motion2robot.motion.prompts import prompts_beside
from motion2robot.motion.safe_pickle import load_npy

HUMANML3D_FPS = 20.0
#: Joint counts whose first 22 joints are the SMPL body in HumanML3D order (SMPL, SMPL-H).
_SMPL_SUPERSETS = (22, 24, 52)
#: Above this RMS of (x - Mean) / Std, a feature array is taken to be normalised already.
NORMALISED_RMS = 5.0


def _pick(items: list[Any], clip: int | None, path: Path) -> list[tuple[int, Any]]:
    if not items:
        raise fail(path, "holds no motion clips (its batch dimension is 0)", "give a file with at least one clip")
    if clip is None:
        return list(enumerate(items))
    if not -len(items) <= clip < len(items):
        raise fail(path, f"has {len(items)} clip(s), --clip {clip} is out of range",
                   f"pass --clip between 0 and {len(items) - 1}")
    return [(clip % len(items), items[clip])]


def _canon(path: Path, pos: np.ndarray, fps: float, opts: ReadOptions, fmt: str, clip: int,
           contacts: np.ndarray | None = None, **meta: Any) -> HumanMotion:
    return canonicalize(
        path, pos, opts.fps or fps,
        up=opts.up or "y", up_source="--up" if opts.up else "the format: HumanML3D space is y up",
        units=opts.units or "m", units_source="--units" if opts.units else "the format: HumanML3D space is in metres",
        contacts=contacts, source_fps=fps,
        meta={"source": str(path), "format": fmt, "clip": clip, **meta})


def _joints_clips(path: Path, arr: np.ndarray) -> list[np.ndarray]:
    """(T, J, 3), (N, T, J, 3) (MotionGPT / T2M-GPT write N = 1) or MLD's "all in one"
    (samples, repetitions, T, J, 3), J in 22/24/52 -> list of (T, 22, 3), sample-major."""
    if arr.ndim == 3 and arr.shape[1] in _SMPL_SUPERSETS and arr.shape[2] == 3:
        return [arr[:, :22]]
    if arr.ndim in (4, 5) and arr.shape[-2] in _SMPL_SUPERSETS and arr.shape[-1] == 3:
        return [a[:, :22] for a in arr.reshape(-1, *arr.shape[-3:])]
    raise fail(path, f"has shape {arr.shape}, not HumanML3D joints (T, 22, 3) or a batch (N, T, 22, 3)",
               "give 22 SMPL joints per frame, or pass --format")


def _batch_meta(arr: np.ndarray, i: int) -> dict[str, int]:
    """Sample and repetition of clip i of an (S, R, T, J, 3) array ({} for other layouts)."""
    return {"sample": i // arr.shape[1], "repetition": i % arr.shape[1]} if arr.ndim == 5 else {}


def read_joints(path: Path, arr: np.ndarray, opts: ReadOptions) -> list[HumanMotion]:
    """HumanML3D joint positions (T, 22, 3) or a batch (N, T, 22, 3); SMPL/SMPL-H supersets
    (24 / 52 joints) keep their first 22 joints."""
    clips = _joints_clips(path, arr)
    note = {} if arr.shape[-2] == 22 else {"note": f"kept the first 22 of {arr.shape[-2]} joints"}
    prompts = prompts_beside(path, arr.shape[0] if arr.ndim == 5 else len(clips))
    per = len(clips) // len(prompts)
    return [_canon(path, c, HUMANML3D_FPS, opts, "humanml3d_joints", i, prompt=prompts[i // per],
                   **_batch_meta(arr, i), **note)
            for i, c in _pick(clips, opts.clip, path)]


def _stats(path: Path, which: str, given: Any, dim: int) -> np.ndarray | None:
    if not given and not path.is_file():
        return None
    p = Path(given) if given else path.parent / f"{which}.npy"
    if not p.is_file():
        if given:
            raise fail(p, f"--{which.lower()} file not found", "give the path of the data set's statistics file")
        return None
    a = load_npy(p)
    if not isinstance(a, np.ndarray) or a.shape != (dim,):
        raise fail(p, f"has shape {getattr(a, 'shape', type(a).__name__)}, expected ({dim},)",
                   f"give the {which}.npy matching {dim}-d features")
    if a.dtype.kind not in "fiu" or not np.all(np.isfinite(a)):
        raise fail(p, f"holds {a.dtype} values that are not all finite numbers", f"give the data set's {which}.npy")
    return a.astype(np.float64)


def _judged_frames(feat: np.ndarray) -> np.ndarray:
    """(K, dim) the frames of ``feat`` that say whether it is normalised: finite and not all zero
    (a NaN sample or a padded one, refused on its own, does not decide for the others)."""
    flat = feat.reshape(-1, feat.shape[-1])
    keep = np.isfinite(flat).all(axis=1) & np.any(flat != 0, axis=1)
    return flat[keep] if keep.any() else flat


def denormalise(path: Path, feat: np.ndarray, opts: ReadOptions) -> tuple[np.ndarray, str]:
    """Raw features and a sentence saying what was assumed (raw or normalised, which stats)."""
    dim = feat.shape[-1]
    judged = _judged_frames(feat)
    mean = _stats(path, "Mean", opts.mean, dim)
    std = _stats(path, "Std", opts.std, dim)
    if (mean is None) != (std is None):
        raise fail(path, "needs both Mean.npy and Std.npy to denormalise", "pass --mean and --std together")
    if mean is not None:
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # a zero Std entry: inf, not a warning
            rms = float(np.sqrt(np.mean(((judged - mean) / std) ** 2)))
        if rms < NORMALISED_RMS:
            return feat, f"raw (|x - Mean|/Std has RMS {rms:.2f}; statistics not applied)"
        return feat * std + mean, f"normalised (RMS {rms:.1f} as raw), denormalised with the given/adjacent Mean/Std"
    if F.looks_raw(judged):
        return feat, "raw (contact channels are exactly 0/1)"
    height = float(np.median(judged[..., 3]))
    contacts = judged[..., F.contact_slice(dim)]
    if 0.05 < height < 2.5 and contacts.min() > -0.5 and contacts.max() < 1.5:
        return feat, f"raw (root height {height:.2f} m and contact channels in range)"
    raise fail(path, "looks like normalised features (contact channels not 0/1) and no Mean.npy/Std.npy "
                     "beside it", "pass --mean Mean.npy --std Std.npy of the model's data set")


def read_features(path: Path, arr: np.ndarray, opts: ReadOptions,
                  lengths: np.ndarray | None = None) -> list[HumanMotion]:
    """HumanML3D 263-d features (T, 263) or (N, T, 263), raw or normalised; ``lengths`` (N,) the
    valid frames of each sample of a padded batch."""
    if arr.ndim not in (2, 3) or arr.shape[-1] not in F.JOINTS_BY_DIM:
        raise fail(path, f"has shape {arr.shape}, not feature vectors (T, 263)",
                   "give HumanML3D 263-d features, or pass --format")
    if arr.shape[-1] == 251:
        raise fail(path, "holds KIT-ML 251-d features: they decode (21 KIT joints) but the KIT skeleton has "
                         "no SMPL22 name map here", "convert to HumanML3D joints first")
    feat = np.asarray(arr, dtype=np.float64)
    samples = [feat] if feat.ndim == 2 else list(feat)
    if lengths is not None:
        samples = [f[:n] for f, n in zip(samples, lengths)]
    picked = _pick(samples, opts.clip, path)
    for _, f in picked:  # only the samples asked for: a bad one spoils no other sample's row
        check_frames(path, f, "features")
    # normalised or raw is judged on every sample's valid frames together, applied to each
    cat, assumed = denormalise(path, np.concatenate(samples), opts)
    clips = np.split(cat, np.cumsum([len(f) for f in samples])[:-1])
    prompts = prompts_beside(path, len(clips))
    out = []
    for i, _ in picked:
        f = clips[i]
        out.append(_canon(path, F.decode_positions(f), HUMANML3D_FPS, opts, "humanml3d_vecs", i,
                          contacts=F.decode_contacts(f), contacts_source="263-d contact channels",
                          features=assumed, prompt=prompts[i]))
    return out


def frame_counts(path: Path, raw: Any, n: int, t: int, fix: str) -> np.ndarray:
    """(n,) int64 valid frames of each of the n samples of a (padded) batch of t frames, from a
    file's ``lengths`` entry; InputFileError (with ``fix``) unless they are n whole numbers in [0, t]."""
    try:
        arr = np.asarray(raw)
        lengths = arr.astype(np.int64).reshape(-1)
        if arr.dtype.kind not in "iuf" or (arr.dtype.kind == "f" and not np.array_equal(lengths, arr.reshape(-1))):
            raise ValueError("not whole numbers")
    except (TypeError, ValueError, OverflowError):
        raise fail(path, f"'lengths' is {raw!r:.60}, not whole frame counts", fix) from None
    if lengths.size != n:
        raise fail(path, f"has {n} motions but {lengths.size} lengths", fix)
    bad = np.flatnonzero((lengths > t) | (lengths < 0))
    if bad.size:
        raise fail(path, f"lengths exceed the motion array ({t} frames) or are negative: samples {bad.tolist()[:8]} "
                         f"claim {lengths[bad].tolist()[:8]}", fix)
    return lengths


def _mdm_layout(path: Path, motion: np.ndarray) -> np.ndarray:
    """(N, 22, 3, T) -> (N, T, 22, 3)."""
    if motion.ndim != 4 or motion.shape[1] != 22 or motion.shape[2] != 3:
        raise fail(path, f"has motion shape {motion.shape}, expected (N, 22, 3, T)",
                   "give MDM-layout joint positions (N, 22, 3, T)")
    return np.transpose(motion, (0, 3, 1, 2))


def read_mdm_array(path: Path, arr: np.ndarray, opts: ReadOptions) -> list[HumanMotion]:
    """A bare MDM-layout array (N, 22, 3, T); (N, 263, 1, T) feature layout is decoded too."""
    if arr.ndim == 4 and arr.shape[1] == 263 and arr.shape[2] == 1:
        return read_features(path, np.transpose(arr[:, :, 0, :], (0, 2, 1)), opts)
    clips = _mdm_layout(path, np.asarray(arr))
    return [_canon(path, c, HUMANML3D_FPS, opts, "mdm_array", i) for i, c in _pick(list(clips), opts.clip, path)]


def read_mdm_results(path: Path, obj: Any, opts: ReadOptions) -> list[HumanMotion]:
    """MDM results dict: sample i = motion[i, :, :, :lengths[i]] as (T, 22, 3), prompt text[i]."""
    if not isinstance(obj, dict) or "motion" not in obj:
        keys = sorted(map(repr, obj)) if isinstance(obj, dict) else type(obj).__name__
        raise fail(path, f"holds {keys}, not an MDM results dict with 'motion'",
                   "give MDM's results.npy (motion, text, lengths)")
    motion = obj["motion"]
    if not isinstance(motion, np.ndarray):
        raise fail(path, "'motion' is not an array", "give MDM's results.npy")
    fix = "re-save the results with one whole frame count (<= T) per motion in 'lengths'"
    if motion.ndim == 4 and motion.shape[1] == 263:
        clips = np.transpose(motion[:, :, 0, :], (0, 2, 1))
        lengths = frame_counts(path, obj["lengths"], *clips.shape[:2], fix) if "lengths" in obj else None
        return read_features(path, clips, opts, lengths)
    clips = _mdm_layout(path, motion)
    n, t = clips.shape[:2]
    lengths = frame_counts(path, obj.get("lengths", np.full(n, t)), n, t, fix)
    text = obj.get("text", [None] * n)
    if isinstance(text, (str, bytes)) or not isinstance(text, (list, tuple, np.ndarray)) or \
            not all(x is None or isinstance(x, (str, np.str_)) for x in text):
        raise fail(path, f"'text' is {text!r:.60}, not a list of prompts (strings)",
                   "re-save the results with one prompt string per sample")
    if len(text) != n:
        raise fail(path, f"has {n} motions but {len(text)} prompts",
                   "re-save the results with matching motion/text/lengths")
    hint = obj.get("hint")
    hint = hint if isinstance(hint, np.ndarray) and hint.ndim == 4 and len(hint) == n else None
    out = []
    for i, c in _pick(list(clips), opts.clip, path):
        prompt = text[i]
        m = _canon(path, c[: lengths[i]], HUMANML3D_FPS, opts, "mdm_results", i,
                   prompt=str(prompt) if prompt is not None else None)
        if hint is not None:  # OmniControl: the spatial control signal
            from motion2robot.motion.control import from_hint

            m = from_hint(m, hint[i])
        out.append(m)
    return out


def read_npz(path: Path, opts: ReadOptions) -> list[HumanMotion]:
    """.npz with a 'joints' or 'positions' array ((T, 22, 3) or a batch) and 'fps'. Axes and units
    are detected unless --up/--units are given (no convention is implied by .npz)."""
    from motion2robot.motion.archive import read_npz_members

    members = read_npz_members(path, ("joints", "positions", "fps", "lengths"))
    key = next((k for k in ("joints", "positions") if k in members), None)
    if key is None:
        raise fail(path, f"has no 'joints' or 'positions' array (keys: {', '.join(members.names) or 'none'})",
                   "save positions as joints=(T, 22, 3) with fps=...")
    arr = members[key]
    fps = None
    if "fps" in members:
        f = members["fps"]
        fps = check_fps(path, f.item() if f.size == 1 and f.dtype.kind in "fiub" else f, "its 'fps' entry")
    if opts.fps is None and fps is None:
        raise fail(path, "has no 'fps' entry", "save fps=... in the .npz or pass --source-fps")
    clips = _joints_clips(path, arr)
    if "lengths" in members:  # a padded batch: each sample's valid frames
        lengths = frame_counts(path, members["lengths"], len(clips), len(clips[0]) if clips else 0,
                               "save lengths=(N,) whole frame counts (<= T), one per sample of joints")
        clips = [c[:n] for c, n in zip(clips, lengths)]
    return [canonicalize(path, c, opts.fps or fps, up=opts.up, up_source="--up",
                         units=opts.units, units_source="--units", source_fps=fps,
                         meta={"source": str(path), "format": "npz", "clip": i, "key": key})
            for i, c in _pick(clips, opts.clip, path)]

"""Reading any supported motion file (or folder) into canonical :class:`HumanMotion` clips.

The formats, their detection and their readers are the table in :mod:`motion2robot.motion.formats`;
this module walks folders, takes the one-open fast path for .npy files and dispatches. Detection is
always overridable with ``format=``.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from motion2robot.motion.checks import fail
from motion2robot.motion.formats import BY_NAME, FORMATS, SCAN_SUFFIXES, TABLE, detect
from motion2robot.motion.human import HumanMotion
from motion2robot.motion.options import ReadOptions
from motion2robot.motion.probe import Probe
from motion2robot.motion.safe_pickle import load_npy, read_npy_data, read_npy_header
from motion2robot.util.files import UNREADABLE_FIX, special_file, unreadable

_NPY_FORMATS = tuple(f.name for f in TABLE if f.npy)


def _format_of_shape(path: Path, shape: tuple[int, ...], dtype: np.dtype) -> str:
    found = detect(Probe(path, (shape, dtype)))
    if found is not None and found.npy:
        return found.name
    if shape in ((263,), (251,)):
        raise fail(path, f"has shape {shape}: a Mean/Std statistics file, not a motion",
                   "pass it with --mean/--std and read the feature file")
    raise fail(path, f"has shape {shape}, which is no known motion layout (expected (T, 22, 3) joints, "
                     "(T, 263) features or MDM (N, 22, 3, T))", "check the array, or pass --format")


def _refuse_special(path: Path) -> None:
    what = special_file(path)
    if what is not None and what != "is a directory":
        raise fail(path, f"{what}, not a motion file", "give a regular motion file")
    what = unreadable(path)
    if what is not None:
        raise fail(path, what, UNREADABLE_FIX)


def detect_format(path: str | Path) -> str:
    """Format name of a file or folder (see :data:`~motion2robot.motion.formats.TABLE`)."""
    path = Path(path)
    _refuse_special(path)
    if path.is_dir():
        files = _folder_files(path)
        return detect_format(files[0])
    if not path.exists():
        raise fail(path, "does not exist", "check the path")
    if path.stat().st_size == 0:
        raise fail(path, "is empty (0 bytes)", "re-export or re-download the file")
    probe = Probe(path)
    if probe.suffix not in (".bvh", ".asf", ".amc") and probe.is_npy:
        return _format_of_shape(path, probe.npy_shape, probe.npy_dtype)
    found = detect(probe)
    if found is not None:
        return found.name
    if probe.suffix == ".npy":
        raise fail(path, "is not a numpy .npy file (no NUMPY magic bytes)",
                   "give a .npy saved with numpy.save, or pass --format")
    raise fail(path, f"has an unknown format (extension {probe.suffix or 'none'!r})",
               f"pass --format, one of {', '.join(FORMATS)}")


def _folder_files(path: Path) -> list[Path]:
    skip = {"mean.npy", "std.npy"}
    files = sorted(p for p in path.iterdir()
                   if p.is_file() and p.suffix.lower() in SCAN_SUFFIXES and p.name.lower() not in skip)
    if not files:
        raise fail(path, f"is a directory without motion files ({', '.join(SCAN_SUFFIXES)})",
                   "give a motion file, or a folder of HumanML3D .npy clips")
    return files


def _read_npy_content(path: Path, fmt: str, arr: Any, opts: ReadOptions) -> list[HumanMotion]:
    spec = BY_NAME[fmt]
    if fmt not in ("mdm_results", "edit_result") and not isinstance(arr, np.ndarray):
        raise fail(path, f"holds a {type(arr).__name__}, not an array", "give a numeric .npy")
    return spec.read_function()(path, arr, opts)


def _read_npy_once(path: Path, fmt: str | None, opts: ReadOptions) -> list[HumanMotion] | None:
    """Fast path for .npy motion: one open, one header parse, one read. None when the file is not
    a .npy holding one of the numpy formats (the caller then takes the general path, which gives
    the same answers and errors)."""
    if fmt not in (None, *_NPY_FORMATS) or (fmt is None and path.suffix.lower() in (".bvh", ".asf", ".amc")):
        return None
    try:
        fh = open(path, "rb")
    except OSError:  # missing, a directory, unreadable: the general path says which
        return None
    with fh:
        if fh.read(6) != b"\x93NUMPY":
            return None
        fh.seek(0)
        header = read_npy_header(path, fh)
        fmt = fmt or _format_of_shape(path, header.shape, header.dtype)
        if fmt not in _NPY_FORMATS:
            return None
        arr = read_npy_data(path, fh, header)
    return _read_npy_content(path, fmt, arr, opts)


def _read_path(path: Path, fmt: str | None, opts: ReadOptions) -> list[HumanMotion]:
    _refuse_special(path)  # a file of a folder: it may be unreadable too
    fast = _read_npy_once(path, fmt, opts)
    if fast is not None:
        return fast
    return _read_file(path, fmt or detect_format(path), opts)


def _read_file(path: Path, fmt: str, opts: ReadOptions,
               skeleton: str | Path | None = None) -> list[HumanMotion]:
    spec = BY_NAME.get(fmt)
    if spec is None:
        raise fail(path, f"unknown format {fmt!r}", f"use one of {', '.join(FORMATS)}")
    if skeleton is not None:
        opts = replace(opts, skeleton=skeleton)
    if spec.npy:
        return _read_npy_content(path, fmt, load_npy(path), opts)
    return spec.read_function()(path, opts)


def read_motion(path: str | Path, *, format: str | None = None, clip: int | None = None,
                fps: float | None = None, mean: str | Path | None = None, std: str | Path | None = None,
                units: str | None = None, up: str | None = None,
                name_map: str | Path | Mapping[str, Any] | None = None,
                skeleton: str | Path | None = None, stats: str | Path | None = None,
                body_model: str | Path | None = None, strict: bool | None = None,
                trajectory: str | Path | None = None) -> list[HumanMotion]:
    """Read a motion file (or a folder of clips) into canonical clips, one per clip.

    format: override detection (see :data:`FORMATS`); clip: keep only that clip index (for a
    folder: that file); fps: override the file's rate; mean/std: statistics for normalised
    features; units ("m", "cm", "mm", "inch", "cmu") and up ("x", "y", "z") override
    detection; name_map: TOML path or {keypoint: joint spec} for BVH skeletons; skeleton: the
    ASF file of an AMC motion (default: the .asf beside it, e.g. 01.asf for 01_01.amc); stats:
    statistics file of normalised MotionFix/OmniME 207-d features; body_model: the user's SMPL-family
    model file for SMPL parameters (else an approximate skeleton with a warning, or a refusal with
    strict); trajectory: a (T, 2) / (T, 3) root path file the motion was asked to follow, in the file's
    axes and units (attached as ``meta["control_path"]``, see :mod:`~motion2robot.motion.control`).
    Raises :class:`~motion2robot.errors.InputFileError` with a one-line message on bad input.
    """
    path = Path(path)
    if format is not None and format not in FORMATS:
        raise fail(path, f"unknown --format {format!r}", f"use one of {', '.join(FORMATS)}")
    opts = ReadOptions(clip, fps, mean, std, units, up, name_map, skeleton, stats=stats, body_model=body_model,
                       strict=bool(strict))
    if trajectory is None:
        return _read_any(path, format, opts)
    from motion2robot.motion.control import from_trajectory, load_trajectory

    arr = load_trajectory(trajectory)  # a bad path file stops before the motion is read
    return [from_trajectory(m, trajectory, arr) for m in _read_any(path, format, opts)]


def _read_any(path: Path, format: str | None, opts: ReadOptions) -> list[HumanMotion]:
    clip = opts.clip
    _refuse_special(path)  # a FIFO would block the open below for ever
    fast = _read_npy_once(path, format, opts)  # a .npy file: one open
    if fast is not None:
        return fast
    if path.is_dir():
        if path.suffix.lower() in SCAN_SUFFIXES:
            raise fail(path, "is a directory, not a motion file", "give the file itself")
        files = _folder_files(path)
        picked = [files[clip]] if clip is not None else files
        if clip is not None and not -len(files) <= clip < len(files):
            raise fail(path, f"holds {len(files)} files, --clip {clip} is out of range",
                       f"pass --clip between 0 and {len(files) - 1}")
        sub = replace(opts, clip=None)
        out = []
        for i, f in enumerate(picked):
            for m in _read_path(f, format, sub):
                out.append(m.with_(meta={"clip": clip if clip is not None else i, "folder": str(path)}))
        return out
    if not path.exists():
        raise fail(path, "does not exist", "check the path")
    return _read_file(path, format or detect_format(path), opts)

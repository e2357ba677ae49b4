"""Reading any supported motion file (or folder) into canonical :class:`HumanMotion` clips.

Formats: "humanml3d_joints", "humanml3d_vecs", "kit_vecs" (refused: no SMPL22 map for KIT),
"mdm_results", "mdm_array", "bvh", "npz", "pt", "amass" and "aistpp_smpl" (refused: SMPL body
model needed), "asf_amc". Detection uses the extension, then the array shape / content; always
overridable with ``format=``.
"""

from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from motion2robot.motion import read_arrays as R
from motion2robot.motion.checks import fail
from motion2robot.motion.human import HumanMotion
from motion2robot.motion.options import ReadOptions
from motion2robot.motion.safe_pickle import load_npy, read_npy_data, read_npy_header, restricted_load
from motion2robot.util.files import special_file

FORMATS = ("humanml3d_joints", "humanml3d_vecs", "kit_vecs", "mdm_results", "mdm_array", "bvh",
           "npz", "pt", "amass", "aistpp_smpl", "asf_amc")
_NPY_FORMATS = ("humanml3d_joints", "humanml3d_vecs", "kit_vecs", "mdm_array", "mdm_results")
_MOTION_SUFFIXES = (".npy", ".npz", ".bvh", ".pt", ".amc")
_SMPL_REFUSAL = ("holds SMPL body-model parameters (axis-angle poses); turning them into joint "
                 "positions needs the licence-restricted SMPL/SMPL-H model files, which are not shipped",
                 "export joint positions (e.g. HumanML3D joints or BVH) and read those instead")


def _npy_shape(path: Path) -> tuple[tuple[int, ...], np.dtype]:
    with open(path, "rb") as fh:
        header = read_npy_header(path, fh)
    return header.shape, header.dtype


def _format_of_shape(path: Path, shape: tuple[int, ...], dtype: np.dtype) -> str:
    if dtype.hasobject:
        return "mdm_results"
    if len(shape) >= 2 and shape[-1] == 263:
        return "humanml3d_vecs"
    if len(shape) >= 2 and shape[-1] == 251:
        return "kit_vecs"
    if len(shape) == 4 and shape[1:3] in ((22, 3), (263, 1)):
        return "mdm_array"
    if (len(shape) == 3 and shape[1] in (22, 24, 52) and shape[2] == 3) or (
            len(shape) == 4 and shape[2] in (22, 24, 52) and shape[3] == 3):
        return "humanml3d_joints"
    if shape in ((263,), (251,)):
        raise fail(path, f"has shape {shape}: a Mean/Std statistics file, not a motion",
                   "pass it with --mean/--std and read the feature file")
    raise fail(path, f"has shape {shape}, which is no known motion layout (expected (T, 22, 3) joints, "
                     "(T, 263) features or MDM (N, 22, 3, T))", "check the array, or pass --format")


def _refuse_special(path: Path) -> None:
    what = special_file(path)
    if what is not None and what != "is a directory":
        raise fail(path, f"{what}, not a motion file", "give a regular motion file")


def detect_format(path: str | Path) -> str:
    """Format name of a file or folder, from its extension, then shape / content."""
    path = Path(path)
    _refuse_special(path)
    if path.is_dir():
        files = _folder_files(path)
        return detect_format(files[0])
    if not path.exists():
        raise fail(path, "does not exist", "check the path")
    suffix = path.suffix.lower()
    if path.stat().st_size == 0:
        raise fail(path, "is empty (0 bytes)", "re-export or re-download the file")
    if suffix == ".bvh":
        return "bvh"
    if suffix in (".asf", ".amc"):
        return "asf_amc"
    with open(path, "rb") as fh:
        head = fh.read(64)
    if head.startswith(b"\x93NUMPY"):
        return _format_of_shape(path, *_npy_shape(path))
    if head.startswith(b"PK"):
        try:
            with zipfile.ZipFile(path) as z:
                names = z.namelist()
        except zipfile.BadZipFile:
            raise fail(path, "is a damaged zip/.npz file", "re-export the file") from None
        if any(n.endswith("data.pkl") for n in names) or suffix == ".pt":
            return "pt"
        keys = {n[:-4] for n in names if n.endswith(".npy")}
        if {"poses", "trans"} <= keys:
            return "amass"
        return "npz"
    if suffix == ".pt":
        return "pt"
    if suffix == ".pkl":
        return "aistpp_smpl"
    if head.lstrip().startswith(b"HIERARCHY"):
        return "bvh"
    if suffix == ".npy":
        raise fail(path, "is not a numpy .npy file (no NUMPY magic bytes)",
                   "give a .npy saved with numpy.save, or pass --format")
    raise fail(path, f"has an unknown format (extension {suffix or 'none'!r})",
               f"pass --format, one of {', '.join(FORMATS)}")


def _folder_files(path: Path) -> list[Path]:
    skip = {"mean.npy", "std.npy"}
    files = sorted(p for p in path.iterdir()
                   if p.is_file() and p.suffix.lower() in _MOTION_SUFFIXES and p.name.lower() not in skip)
    if not files:
        raise fail(path, "is a directory without motion files (.npy, .npz, .bvh, .pt, .amc)",
                   "give a motion file, or a folder of HumanML3D .npy clips")
    return files


def _read_pkl(path: Path, opts: ReadOptions) -> list[HumanMotion]:
    with open(path, "rb") as fh:
        obj = restricted_load(path, fh)
    if isinstance(obj, dict) and "smpl_poses" in obj:
        raise fail(path, *_SMPL_REFUSAL)
    raise fail(path, f"holds a {type(obj).__name__}, not a known motion pickle", "pass --format")


def _read_npy_content(path: Path, fmt: str, arr: Any, opts: ReadOptions) -> list[HumanMotion]:
    if fmt == "mdm_results":
        return R.read_mdm_results(path, arr, opts)
    if not isinstance(arr, np.ndarray):
        raise fail(path, f"holds a {type(arr).__name__}, not an array", "give a numeric .npy")
    reader = {"humanml3d_joints": R.read_joints, "humanml3d_vecs": R.read_features,
              "kit_vecs": R.read_features, "mdm_array": R.read_mdm_array}[fmt]
    return reader(path, arr, opts)


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


def _read_path(path: Path, fmt: str | None, opts: ReadOptions,
               skeleton: str | Path | None = None) -> list[HumanMotion]:
    fast = _read_npy_once(path, fmt, opts)
    if fast is not None:
        return fast
    return _read_file(path, fmt or detect_format(path), opts, skeleton)


def _read_file(path: Path, fmt: str, opts: ReadOptions,
               skeleton: str | Path | None = None) -> list[HumanMotion]:
    if fmt in _NPY_FORMATS:
        return _read_npy_content(path, fmt, load_npy(path), opts)
    if fmt == "bvh":
        from motion2robot.motion.read_bvh import read_bvh
        return read_bvh(path, opts)
    if fmt == "npz":
        return R.read_npz(path, opts)
    if fmt == "pt":
        from motion2robot.motion.tensors import read_pt
        return read_pt(path, opts)
    if fmt == "amass":
        raise fail(path, *_SMPL_REFUSAL)
    if fmt == "aistpp_smpl":
        return _read_pkl(path, opts)
    if fmt == "asf_amc":
        from motion2robot.motion.read_asf_amc import read_asf_amc
        return read_asf_amc(path, opts, skeleton)
    raise fail(path, f"unknown format {fmt!r}", f"use one of {', '.join(FORMATS)}")


def read_motion(path: str | Path, *, format: str | None = None, clip: int | None = None,
                fps: float | None = None, mean: str | Path | None = None, std: str | Path | None = None,
                units: str | None = None, up: str | None = None,
                name_map: str | Path | Mapping[str, Any] | None = None,
                skeleton: str | Path | None = None) -> list[HumanMotion]:
    """Read a motion file (or a folder of clips) into canonical clips, one per clip.

    format: override detection (see :data:`FORMATS`); clip: keep only that clip index (for a
    folder: that file); fps: override the file's rate; mean/std: statistics for normalised
    features; units ("m", "cm", "mm", "inch", "cmu") and up ("x", "y", "z") override
    detection; name_map: TOML path or {keypoint: joint spec} for BVH skeletons; skeleton: the
    ASF file of an AMC motion (default: the .asf beside it, e.g. 01.asf for 01_01.amc).
    Raises :class:`~motion2robot.errors.InputFileError` with a one-line message on bad input.
    """
    path = Path(path)
    if format is not None and format not in FORMATS:
        raise fail(path, f"unknown --format {format!r}", f"use one of {', '.join(FORMATS)}")
    opts = ReadOptions(clip, fps, mean, std, units, up, name_map)
    _refuse_special(path)  # a FIFO would block the open below for ever
    fast = _read_npy_once(path, format, opts)  # a .npy file: one open
    if fast is not None:
        return fast
    if path.is_dir():
        if path.suffix.lower() in _MOTION_SUFFIXES:
            raise fail(path, "is a directory, not a motion file", "give the file itself")
        files = _folder_files(path)
        picked = [files[clip]] if clip is not None else files
        if clip is not None and not -len(files) <= clip < len(files):
            raise fail(path, f"holds {len(files)} files, --clip {clip} is out of range",
                       f"pass --clip between 0 and {len(files) - 1}")
        sub = ReadOptions(None, fps, mean, std, units, up, name_map)
        out = []
        for i, f in enumerate(picked):
            for m in _read_path(f, format, sub, skeleton):
                out.append(m.with_(meta={"clip": clip if clip is not None else i, "folder": str(path)}))
        return out
    if not path.exists():
        raise fail(path, "does not exist", "check the path")
    return _read_file(path, format or detect_format(path), opts, skeleton)

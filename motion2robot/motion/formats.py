"""The table of motion formats: one :class:`Format` per format, in detection order.

Detection (:func:`motion2robot.motion.read.detect_format`), reading, ``batch``'s folder scan and the
CLI's ``--format`` help all come from :data:`TABLE`. Adding a format is one reader module plus one
:class:`Format` line here: its name, the file endings scanned in folders, a detector on a
:class:`~motion2robot.motion.probe.Probe` (suffix, first bytes, .npy header, zip member names),
the reader ("module:function", imported on first use so optional dependencies stay optional),
whether a file holds one clip or many, and the reader options it takes.

Readers take ``(path, content, opts)`` when ``npy`` is set (content: the .npy's array, or the
restricted-unpickled object of an object array) and ``(path, opts)`` otherwise.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any, Callable

from motion2robot.motion.probe import Probe

#: Reader options every format takes (ReadOptions fields); ``Format.options`` lists the others.
COMMON_OPTIONS = ("clip", "fps", "units", "up")


@dataclass(frozen=True)
class Format:
    """One readable motion format.

    name: the ``--format`` value; summary: one line for help texts; suffixes: file endings picked up
    when a folder is scanned (read_motion on a folder, batch); detect: True when a probed file is
    this format (tried in table order); reader: "module:function"; npy: the reader takes the .npy's
    content; single_clip: a file never holds more than one clip; options: reader options it uses
    beyond :data:`COMMON_OPTIONS`.
    """

    name: str
    summary: str
    suffixes: tuple[str, ...]
    detect: Callable[[Probe], bool]
    reader: str
    npy: bool = False
    single_clip: bool = False
    options: tuple[str, ...] = ()

    def read_function(self) -> Callable[..., Any]:
        module, func = self.reader.split(":")
        return getattr(importlib.import_module(module), func)


def _npy_last(*dims: int) -> Callable[[Probe], bool]:
    return lambda p: p.is_npy and not p.npy_dtype.hasobject and len(p.npy_shape) >= 2 and p.npy_shape[-1] in dims


def _npy_joints(p: Probe) -> bool:
    s = p.npy_shape if p.is_npy and not p.npy_dtype.hasobject else ()
    return len(s) in (3, 4, 5) and s[-2] in (22, 24, 52) and s[-1] == 3


def _mdm_array(p: Probe) -> bool:
    s = p.npy_shape if p.is_npy and not p.npy_dtype.hasobject else ()
    return len(s) == 4 and s[1:3] in ((22, 3), (263, 1))


_A = "motion2robot.motion.read_arrays"

#: Every readable format, in detection order (the first whose detector says yes wins).
TABLE: tuple[Format, ...] = (
    Format("bvh", "BVH mocap / rig animation (any skeleton with recognisable joint names)", (".bvh",),
           lambda p: p.suffix == ".bvh" or p.text_starts("HIERARCHY"),
           "motion2robot.motion.read_bvh:read_bvh", single_clip=True, options=("name_map",)),
    Format("asf_amc", "CMU ASF/AMC take (the .asf skeleton beside the .amc)", (".amc",),
           lambda p: p.suffix in (".asf", ".amc"),
           "motion2robot.motion.read_asf_amc:read_asf_amc", single_clip=True, options=("skeleton",)),
    Format("edit_result", "MotionFix/OmniME result .npy (pickled dict: pose, pose_source, pose_target (T,135), "
           "text): clips edited, source, target", (".npy",),
           lambda p: p.is_npy and p.npy_dtype.hasobject and "pose" in p.npy_object_keys,
           "motion2robot.motion.read_smpl:read_edit_result", npy=True, options=("body_model", "strict")),
    Format("mdm_results", "MDM-style results.npy (pickled dict: motion (N,22,3,T), text, lengths)", (".npy",),
           lambda p: p.is_npy and p.npy_dtype.hasobject, f"{_A}:read_mdm_results", npy=True,
           options=("mean", "std")),
    Format("humanml3d_vecs", "HumanML3D 263-d feature vectors (T,263), raw or normalised", (".npy",),
           _npy_last(263), f"{_A}:read_features", npy=True, options=("mean", "std")),
    Format("kit_vecs", "KIT-ML 251-d feature vectors (refused: no SMPL22 map for KIT)", (".npy",),
           _npy_last(251), f"{_A}:read_features", npy=True, options=("mean", "std")),
    Format("smplh_135", "SMPL-H rotations (T,135): translation + 22 6D rotations (MotionFix/OmniME), z up, "
           "30 fps", (".npy",), _npy_last(135), "motion2robot.motion.read_smpl:read_smplh_135", npy=True,
           options=("body_model", "strict")),
    Format("motionfix_207", "MotionFix/OmniME 207-d features (T,207), z up, 30 fps, raw or normalised", (".npy",),
           _npy_last(207), "motion2robot.motion.motionfix:read_motionfix", npy=True, options=("stats",)),
    Format("mdm_array", "bare MDM-layout array (N,22,3,T)", (".npy",),
           _mdm_array, f"{_A}:read_mdm_array", npy=True, options=("mean", "std")),
    Format("humanml3d_joints", "HumanML3D joint positions (T,22,3), a batch (N,T,22,3) or MLD's "
           "(samples,repetitions,T,22,3); a .txt beside it is the prompt", (".npy",),
           _npy_joints, f"{_A}:read_joints", npy=True),
    Format("pt", "torch .pt/.pth tensor (needs motion2robot[torch])", (".pt", ".pth"),
           lambda p: (p.is_zip and (p.zip_has_suffix("data.pkl") or p.suffix == ".pt"))
           or (p.suffix == ".pt" and not p.is_npy and not p.is_zip),
           "motion2robot.motion.tensors:read_pt"),
    Format("amass", "AMASS SMPL-H / SMPL-X parameters .npz (poses or root_orient + pose_body, trans, betas)",
           (".npz",), lambda p: p.is_zip and ({"poses", "trans"} <= p.npz_keys
                                              or {"root_orient", "pose_body"} <= p.npz_keys),
           "motion2robot.motion.read_smpl:read_amass", single_clip=True, options=("body_model", "strict")),
    Format("npz", ".npz with joints=(T,22,3) or (N,T,22,3), fps, optional lengths=(N,)", (".npz",),
           lambda p: p.is_zip, f"{_A}:read_npz"),
    Format("aistpp_smpl", "AIST++ SMPL parameters .pkl (or an editor result dict), restricted unpickler",
           (".pkl",), lambda p: p.suffix == ".pkl", "motion2robot.motion.read_smpl:read_smpl_pkl",
           options=("body_model", "strict")),
)

BY_NAME: dict[str, Format] = {f.name: f for f in TABLE}
#: Format names, in table order (the ``--format`` choices).
FORMATS: tuple[str, ...] = tuple(BY_NAME)
#: File endings picked up when a folder is scanned.
SCAN_SUFFIXES: tuple[str, ...] = tuple(dict.fromkeys(s for f in TABLE for s in f.suffixes))
#: File endings whose every format holds exactly one clip (batch counts them without reading).
SINGLE_CLIP_SUFFIXES: tuple[str, ...] = tuple(
    s for s in SCAN_SUFFIXES if all(f.single_clip for f in TABLE if s in f.suffixes))


def detect(probe: Probe) -> Format | None:
    """The first format of the table whose detector accepts the probed file, or None."""
    for f in TABLE:
        if f.detect(probe):
            return f
    return None


def formats_using(option: str) -> tuple[str, ...]:
    """Names of the formats whose reader uses ``option`` (a ReadOptions field)."""
    return tuple(f.name for f in TABLE if option in f.options)


def format_help() -> str:
    """The ``--format`` help: every format with its summary."""
    return "override format detection: " + "; ".join(f"{f.name}: {f.summary}" for f in TABLE)

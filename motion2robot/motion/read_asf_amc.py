"""CMU ASF/AMC takes -> canonical HumanMotion: find the skeleton, parse, FK, map onto SMPL22,
canonicalise.

The skeleton of ``01_01.amc`` is the ``.asf`` beside it named by the same stem or a ``_``-prefix
of it (``01_01.asf``, then ``01.asf``), else the only ``.asf`` in that folder, unless given
explicitly (``skeleton=``). An ``.asf`` alone holds no motion and is refused.

Keypoints: an ASF bone's position is its END point, while a BVH joint sits at the START of its
segment. Each bone's start is named after the joint of the cgspeed CMU BVH conversion
(:data:`ASF_TO_BVH`: ``lfemur`` starts at ``LeftUpLeg`` = the hip, ``ltibia`` at ``LeftLeg`` =
the knee, i.e. the END of ``lfemur``), and the result goes through the same "cmu" name map the BVH
reader uses (:data:`~motion2robot.motion.skeletons.PRESETS`). So: hip = end of l/rhipjoint,
knee = end of femur, ankle = end of tibia, foot (toe base) = end of foot, collar = end of thorax,
shoulder = end of clavicle, elbow = end of humerus, wrist = end of radius, spine1 = end of
lowerback, spine2 = end of upperback, neck = end of lowerneck, head = end of upperneck. A leaf
bone's end is "<Name>_End" (e.g. ``Head_End`` = top of the head). A ``--name-map`` uses these
names. Unlike the cgspeed BVH (which drops the thorax and lwrist lengths), the ASF keeps every
bone, so neck/head/arm keypoints sit one thorax length (~11.7 cm for subject 01) further along
the spine than in that BVH.

Axes: y up (the CMU convention; ``--up`` overrides). Units: from ``:units length L``
(1 unit = 1/L inch; CMU's 0.45 = "cmu" units, 5.644 cm). Frame rate: AMC stores none; CMU
captures at 120 fps (``--source-fps`` overrides).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2robot.motion.asf_amc import forward_kinematics, parse_amc, parse_asf
from motion2robot.motion.canonical import canonicalize
from motion2robot.motion.checks import fail
from motion2robot.motion.human import HumanMotion
from motion2robot.motion.options import ReadOptions
from motion2robot.motion.read_bvh import _user_map, keypoint_positions
from motion2robot.motion.skeletons import choose_map

#: CMU's capture rate; AMC files do not store one.
CMU_FPS = 120.0
#: ``:units length`` of CMU ASF files (1 unit = 1/0.45 inch).
CMU_LENGTH_UNIT = 0.45


def _sided(common: dict[str, str], sided: dict[str, str]) -> dict[str, str]:
    out = dict(common)
    for asf, bvh in sided.items():
        out["l" + asf] = bvh.replace("{S}", "Left").replace("{s}", "L")
        out["r" + asf] = bvh.replace("{S}", "Right").replace("{s}", "R")
    return out


#: CMU ASF bone -> the cgspeed BVH joint at that bone's START.
ASF_TO_BVH: dict[str, str] = _sided(
    {"root": "Hips", "lowerback": "LowerBack", "upperback": "Spine", "thorax": "Spine1",
     "lowerneck": "Neck", "upperneck": "Neck1", "head": "Head"},
    {"hipjoint": "{s}HipJoint", "femur": "{S}UpLeg", "tibia": "{S}Leg", "foot": "{S}Foot",
     "toes": "{S}ToeBase", "clavicle": "{S}Shoulder", "humerus": "{S}Arm", "radius": "{S}ForeArm",
     "wrist": "{S}Hand", "hand": "{S}FingerBase", "fingers": "{s}Fingers", "thumb": "{s}Thumb"})


def find_skeleton(amc: Path) -> Path:
    """The ASF beside ``amc`` (see the module docstring); InputFileError when there is none."""
    parts = amc.stem.split("_")
    stems = ["_".join(parts[:k]) for k in range(len(parts), 0, -1)]
    asfs = {p.name.lower(): p for p in amc.parent.iterdir() if p.is_file() and p.suffix.lower() == ".asf"}
    for stem in stems:
        if f"{stem.lower()}.asf" in asfs:
            return asfs[f"{stem.lower()}.asf"]
    if len(asfs) == 1:
        return next(iter(asfs.values()))
    looked = " or ".join(f"{s}.asf" for s in stems)
    where = f"no {looked} beside it" if not asfs else f"no {looked} among the {len(asfs)} .asf files beside it"
    raise fail(amc, f"is an AMC motion without its ASF skeleton ({where})",
               "put the subject's .asf beside it (e.g. 01.asf for 01_01.amc) or pass --skeleton FILE.asf")


def _refuse_lone_asf(path: Path) -> None:
    takes = sorted(p.name for p in path.parent.glob("*") if p.suffix.lower() == ".amc")
    example = next((t for t in takes if t.lower().startswith(path.stem.lower() + "_")), takes[0] if takes else None)
    raise fail(path, "is an ASF skeleton without motion",
               f"read the .amc take instead (e.g. {example}), with this .asf beside it" if example else
               "read an .amc take of this subject, with this .asf beside it (or pass --skeleton)")


def _units(skeleton_length_unit: float | None, opts: ReadOptions, asf: Path) -> tuple[float, str | None, str]:
    """(factor applied to raw lengths, units name for canonicalize or None to detect, source)."""
    if opts.units is not None:
        return 1.0, opts.units, "--units"
    lu = skeleton_length_unit
    if lu is None:
        return 1.0, None, ""
    if abs(lu - CMU_LENGTH_UNIT) < 1e-9:
        return 1.0, "cmu", f"format ({asf.name} ':units length 0.45': CMU units, 1/0.45 inch)"
    return 1.0 / lu, "inch", f"format ({asf.name} ':units length {lu:g}': 1 unit = 1/{lu:g} inch)"


def read_asf_amc(path: Path, opts: ReadOptions, skeleton: str | Path | None = None) -> list[HumanMotion]:
    """One clip per AMC take; ``skeleton``: the .asf (default: ``opts.skeleton``, else found beside the .amc)."""
    skeleton = skeleton if skeleton is not None else opts.skeleton
    if path.suffix.lower() == ".asf" and skeleton is None:
        _refuse_lone_asf(path)
    if opts.clip not in (None, 0, -1):
        raise fail(path, f"holds one clip, --clip {opts.clip} is out of range", "pass --clip 0 or omit it")
    asf = Path(skeleton) if skeleton is not None else find_skeleton(path)
    if not asf.is_file():
        raise fail(asf, "does not exist (the --skeleton given for an AMC motion)", "give the subject's .asf file")
    sk = parse_asf(asf)
    motion = parse_amc(path, sk, asf)
    root, ends = forward_kinematics(sk, motion)
    joints: dict[str, np.ndarray] = {}
    for bone in sk.order:
        start = ends[sk.parents[bone]] if sk.parents[bone] != "root" else root
        name = ASF_TO_BVH.get(bone, bone)
        joints[name] = start
        if not any(p == bone for p in sk.parents.values()):
            joints[f"{name}_End"] = ends[bone]
    joints["Hips"] = root
    preset, mapping = choose_map(path, list(joints), _user_map(opts))
    factor, units, units_source = _units(sk.length_unit, opts, asf)
    pos = keypoint_positions(joints, mapping) * factor
    fps = opts.fps or CMU_FPS
    note = f"skeleton {asf.name}" + ("" if opts.fps else f"; AMC stores no frame rate, CMU's {CMU_FPS:g} fps assumed")
    return [canonicalize(
        path, pos, fps, up=opts.up or "y", up_source="--up" if opts.up else "format (CMU ASF/AMC is y up)",
        units=units, units_source=units_source, source_fps=None if opts.fps else CMU_FPS,
        meta={"source": str(path), "format": "asf_amc", "clip": 0, "skeleton": preset, "asf": str(asf),
              "first_frame": motion.first_frame, "note": note})]

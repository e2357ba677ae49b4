"""Name maps from common BVH skeletons onto the 22 SMPL keypoints.

A map gives, for each SMPL22 keypoint, a spec in a small language:
``"Joint"`` (one joint), ``"A+B"`` (the midpoint of A and B, for skeletons with fewer spine
joints), and ``"X|Y"`` (alternatives, first present wins). ``"<Joint>_End"`` is the End Site
below a joint (IK-generated files end chains there). Names match case-insensitively and ignore a
namespace prefix ("mixamorig:Hips" == "Hips"). A user map is a TOML file with a ``[keypoints]``
table (or top-level keys) in the same language; a TOML list means the midpoint of its joints.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Mapping

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from motion2robot.motion.checks import fail
from motion2robot.motion.human import SMPL22


def _sided(common: dict[str, str], sided: dict[str, str], left: str, right: str) -> dict[str, str]:
    """Expand {"hip": "{S}UpLeg"} with side tokens into left_/right_ keypoints ({s}: L / R)."""
    out = dict(common)
    for kp, pat in sided.items():
        out[f"left_{kp}"] = pat.replace("{S}", left).replace("{s}", "L")
        out[f"right_{kp}"] = pat.replace("{S}", right).replace("{s}", "R")
    return out


#: Known skeletons, most specific first. Each fully maps SMPL22.
PRESETS: dict[str, dict[str, str]] = {
    # cgspeed/Xia CMU conversions: Hips, LHipJoint, LeftUpLeg ..., LowerBack, Spine, Spine1, Neck1, Head
    "cmu": _sided(
        {"pelvis": "Hips", "spine1": "Spine", "spine2": "Spine1", "spine3": "Spine1+Neck1",
         "neck": "Neck1", "head": "Head"},
        {"hip": "{S}UpLeg", "knee": "{S}Leg", "ankle": "{S}Foot", "foot": "{S}ToeBase",
         "collar": "{S}Shoulder", "shoulder": "{S}Arm", "elbow": "{S}ForeArm", "wrist": "{S}Hand"},
        "Left", "Right"),
    # LAFAN1/Ubisoft, Mixamo, MoMask/SMPL templates: Hips, LeftUpLeg, Spine, Spine1, Spine2, Neck, Head
    "mixamo_lafan": _sided(
        {"pelvis": "Hips", "spine1": "Spine", "spine2": "Spine1", "spine3": "Spine2",
         "neck": "Neck", "head": "Head"},
        {"hip": "{S}UpLeg", "knee": "{S}Leg", "ankle": "{S}Foot", "foot": "{S}Toe|{S}ToeBase|{S}Foot_End",
         "collar": "{S}Shoulder", "shoulder": "{S}Arm", "elbow": "{S}ForeArm", "wrist": "{S}Hand"},
        "Left", "Right"),
    # SMPL joint names (L_Hip ...); IK exports end chains at End Sites instead of foot/head/wrist
    "smpl": _sided(
        {"pelvis": "Pelvis", "spine1": "Spine1", "spine2": "Spine2", "spine3": "Spine3",
         "neck": "Neck", "head": "Head|Neck_End"},
        {"hip": "{S}_Hip", "knee": "{S}_Knee", "ankle": "{S}_Ankle", "foot": "{S}_Foot|{S}_Ankle_End",
         "collar": "{S}_Collar", "shoulder": "{S}_Shoulder", "elbow": "{S}_Elbow",
         "wrist": "{S}_Wrist|{S}_Elbow_End"},
        "L", "R"),
    # Unity humanoid names (Hips, Spine, Chest, UpperChest, LeftUpperLeg ...), as written by IK tools
    "unity_humanoid": _sided(
        {"pelvis": "Hips", "spine1": "Spine", "spine2": "Chest", "spine3": "UpperChest",
         "neck": "Neck", "head": "Head|Neck_End"},
        {"hip": "{S}UpperLeg", "knee": "{S}LowerLeg", "ankle": "{S}Foot", "foot": "{S}Toes|{S}Foot_End|{s}_Foot",
         "collar": "{S}Shoulder", "shoulder": "{S}UpperArm", "elbow": "{S}LowerArm",
         "wrist": "{S}Hand|{S}LowerArm_End|{s}_Wrist"},
        "Left", "Right"),
    # Bandai Namco Research Motiondataset: joint_Root, Hips, Spine, Chest, Neck, Head, UpperLeg_L ...
    "bandai_namco": _sided(
        {"pelvis": "Hips", "spine1": "Spine", "spine2": "Chest", "spine3": "Chest+Neck",
         "neck": "Neck", "head": "Head"},
        {"hip": "UpperLeg_{S}", "knee": "LowerLeg_{S}", "ankle": "Foot_{S}", "foot": "Toes_{S}",
         "collar": "Shoulder_{S}", "shoulder": "UpperArm_{S}", "elbow": "LowerArm_{S}", "wrist": "Hand_{S}"},
        "L", "R"),
    # 100STYLE: Hips, Chest..Chest4, Neck, Head, LeftHip, LeftKnee, LeftAnkle, LeftToe, LeftCollar ...
    "100style": _sided(
        {"pelvis": "Hips", "spine1": "Chest", "spine2": "Chest3", "spine3": "Chest4",
         "neck": "Neck", "head": "Head"},
        {"hip": "{S}Hip", "knee": "{S}Knee", "ankle": "{S}Ankle", "foot": "{S}Toe",
         "collar": "{S}Collar", "shoulder": "{S}Shoulder", "elbow": "{S}Elbow", "wrist": "{S}Wrist"},
        "Left", "Right"),
    # Reallusion Character Creator rig (CC_Base_*), with or without RL_BoneRoot
    "character_creator": _sided(
        {"pelvis": "CC_Base_Hip", "spine1": "CC_Base_Waist", "spine2": "CC_Base_Spine01",
         "spine3": "CC_Base_Spine02", "neck": "CC_Base_NeckTwist01", "head": "CC_Base_Head"},
        {"hip": "CC_Base_{S}_Thigh", "knee": "CC_Base_{S}_Calf", "ankle": "CC_Base_{S}_Foot",
         "foot": "CC_Base_{S}_ToeBase", "collar": "CC_Base_{S}_Clavicle", "shoulder": "CC_Base_{S}_Upperarm",
         "elbow": "CC_Base_{S}_Forearm", "wrist": "CC_Base_{S}_Hand"},
        "L", "R"),
}


def _norm(name: str) -> str:
    return name.rsplit(":", 1)[-1].strip().lower()


def _resolve_spec(spec: str, by_norm: Mapping[str, str]) -> list[str] | None:
    """Joint names (file spelling) whose mean gives the keypoint, or None if not resolvable."""
    for alt in spec.split("|"):
        parts = [by_norm.get(_norm(p)) for p in alt.split("+")]
        if all(parts):
            return parts  # type: ignore[return-value]
    return None


def resolve(name_map: Mapping[str, str], joint_names: list[str]) -> tuple[dict[str, list[str]], list[str]]:
    """({keypoint: [file joints to average]}, [keypoints that could not be mapped])."""
    by_norm = {_norm(n): n for n in joint_names}
    got, missing = {}, []
    for kp in SMPL22:
        spec = name_map.get(kp)
        parts = _resolve_spec(spec, by_norm) if spec else None
        if parts is None:
            missing.append(f"{kp}={spec}" if spec else kp)
        else:
            got[kp] = parts
    return got, missing


def load_name_map(path: str | Path) -> dict[str, str]:
    """Read a user TOML name map ({keypoint: spec}); lists become midpoints ("A+B")."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise fail(path, f"is not a readable TOML name map ({err})",
                   'write lines like pelvis = "Hips" under [keypoints]') from None
    table = data.get("keypoints", data)
    out: dict[str, str] = {}
    for kp, spec in table.items():
        if kp not in SMPL22:
            raise fail(path, f"maps unknown keypoint {kp!r}", f"use SMPL22 names: {', '.join(SMPL22)}")
        if isinstance(spec, list) and spec and all(isinstance(s, str) for s in spec):
            spec = "+".join(spec)
        if not isinstance(spec, str):
            raise fail(path, f"keypoint {kp} must map to a joint name or a list of joint names",
                       f'write {kp} = "JointName"')
        out[kp] = spec
    return out


def choose_map(path: str | Path, joint_names: list[str], user_map: Mapping[str, str] | None = None,
               tree: "SkeletonTree | None" = None) -> tuple[str, dict[str, list[str]]]:
    """The preset, "auto" (names read as tokens and checked against ``tree``, see
    :mod:`~motion2robot.motion.auto_map`) or "user" map (a user map may override a preset or the
    automatic map partly) that maps all 22 keypoints.

    Raises an InputFileError naming the keypoints the closest skeleton could not map.
    """
    candidates = list(PRESETS.items())
    if user_map:
        candidates = [("user", dict(user_map))] + [(f"user+{n}", {**m, **user_map}) for n, m in candidates]
    best: tuple[str, list[str]] | None = None
    for name, m in candidates:
        got, missing = resolve(m, joint_names)
        if not missing:
            return name, got
        if best is None or len(missing) < len(best[1]):
            best = (name, missing)
    if tree is not None:
        from motion2robot.motion.auto_map import auto_map

        got, missing = auto_map(joint_names, *tree)
        if user_map:
            mine, _ = resolve(dict(user_map), joint_names)
            got.update({kp: v for kp, v in mine.items() if kp in user_map})
            missing = [kp for kp in SMPL22 if kp not in got]
        if not missing:
            return ("user+auto" if user_map else "auto"), got
        if best is None or len(missing) < len(best[1]):
            best = ("automatic map from joint names", missing)
    assert best is not None
    shown = ", ".join(joint_names[:12]) + (" ..." if len(joint_names) > 12 else "")
    raise fail(path, f"unknown skeleton: closest known map ({best[0]}) cannot map {len(best[1])} keypoints "
                     f"({', '.join(best[1][:8])}{' ...' if len(best[1]) > 8 else ''}); file joints: {shown}",
               "pass --name-map map.toml with a [keypoints] table (e.g. pelvis = \"Hips\")")


#: (parents, offsets (J, 3), end-site flags) of a skeleton, in joint-name order.
SkeletonTree = tuple


def describe_map(mapping: Mapping[str, list[str]]) -> str:
    """One line: ``pelvis=Hips left_hip=LeftUpLeg ... spine3=Spine1+Neck1``."""
    return " ".join(f"{kp}={'+'.join(mapping[kp])}" for kp in SMPL22 if kp in mapping)

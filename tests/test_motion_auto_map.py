"""Automatic skeleton map: joint names read as tokens, checked against the tree."""

from __future__ import annotations

import random
import re
from pathlib import Path

import numpy as np
import pytest

from motion2robot.errors import InputFileError
from motion2robot.motion import read_motion
from motion2robot.motion.auto_map import auto_map
from motion2robot.motion.bvh import parse_bvh
from motion2robot.motion.name_tokens import classify, words
from motion2robot.motion.skeletons import choose_map
from tests._shared import MOTIONS, requires_shared

SHARED_BVH = sorted((MOTIONS / "bvh").glob("*.bvh")) if MOTIONS else []


@pytest.mark.parametrize("name,side,word", [
    ("Left_hip", "L", "hip"), ("LeftUpLeg", "L", "upleg"), ("l_hip", "L", "hip"),
    ("mixamorig:LeftUpLeg", "L", "upleg"), ("L_Thigh", "L", "thigh"), ("UpperLeg_R", "R", "upperleg"),
    ("lfemur", "L", "femur"), ("LHipJoint", "L", "hip"), ("CC_Base_R_Forearm", "R", "forearm"),
    ("RightToeBase", "R", "toebase"), ("Pelvis", None, "pelvis"), ("CC_Base_Hip", None, "hips"),
    ("Spine02", None, "spine"), ("UpperChest", None, "upperchest"),
])
def test_names_read_as_side_and_part(name: str, side, word: str) -> None:
    w = classify(name)
    assert w is not None and (w.side, w.word) == (side, word), (name, words(name), w)


@pytest.mark.parametrize("name", ["j0_hips", "LeftHandIndex1", "CC_Base_L_ToeBaseShareBone", "LThumb", "Left"])
def test_names_with_unknown_words_have_no_part(name: str) -> None:
    assert classify(name) is None


def _tree(path: Path):
    sk = parse_bvh(path).skeleton
    children = {p for p in sk.parents if p >= 0}
    ends = [not sk.channels[j] and j not in children and j > 0 for j in range(len(sk.names))]
    return list(sk.names), (sk.parents, sk.offsets, ends)


@requires_shared
@pytest.mark.parametrize("path", SHARED_BVH, ids=lambda p: p.name)
def test_automatic_map_equals_the_preset_on_every_shared_bvh(path: Path) -> None:
    names, tree = _tree(path)
    preset, mapping = choose_map(path, names)
    auto, missing = auto_map(names, *tree)
    assert preset != "auto" and not missing and auto == mapping


# Spellings per keypoint part: (part words that mean it unambiguously, words that need a partner word).
_SIDE_FORMS = ("Left{P}", "L_{P}", "l_{p}", "Left_{p}", "{P}_L", "mixamorig:Left{P}", "L{P}")
_PARTS = {
    "hip": ("UpLeg", "Thigh", "UpperLeg", "Femur", "Hip"), "knee": ("Knee", "Calf", "LowerLeg", "Shin"),
    "ankle": ("Ankle", "Foot"), "foot": ("Toe", "ToeBase", "Toes"),
    "collar": ("Clavicle", "Collar"), "shoulder": ("UpperArm", "Arm", "Humerus", "Shoulder"),
    "elbow": ("ForeArm", "Elbow", "LowerArm"), "wrist": ("Hand", "Wrist"),
}


def _spelling(kp: str, rng: random.Random) -> str:
    side, _, part = kp.partition("_") if kp.startswith(("left_", "right_")) else ("", "", kp)
    if side:
        word = rng.choice(_PARTS[part])
        form = rng.choice(_SIDE_FORMS)
        if side == "right":
            form = form.replace("Left", "Right").replace("L_", "R_").replace("_L", "_R").replace("l_", "r_")
            form = "R{P}" if form == "L{P}" else form
        return form.replace("{P}", word).replace("{p}", word.lower())
    if kp == "pelvis":
        return rng.choice(("Pelvis", "Hips", "mixamorig:Hips", "pelvis"))
    if kp.startswith("spine"):
        return rng.choice(("Spine", "Chest", "Torso", "Back")) + kp[-1]
    return rng.choice((kp.capitalize(), kp, f"{kp.capitalize()}_01"))


def _renamed(path: Path, out: Path, seed: int) -> Path:
    """A copy of a BVH whose mapped joints are renamed with random synonyms and side spellings."""
    rng = random.Random(seed)
    names, _ = _tree(path)
    _, mapping = choose_map(path, names)
    new: dict[str, str] = {}
    for kp, joints in mapping.items():
        if len(joints) != 1 or joints[0].endswith("_End") or joints[0] in new:
            continue
        taken = (set(names) - {joints[0]}) | set(new.values())
        for _ in range(100):  # a spelling no other joint of the file already has
            name = _spelling(kp, rng)
            if name not in taken:
                new[joints[0]] = name
                break
    text = re.sub(r"((?:ROOT|JOINT)\s+)(\S+)", lambda m: m.group(1) + new.get(m.group(2), m.group(2)),
                  path.read_text())
    out.write_text(text)
    return out


@requires_shared
@pytest.mark.parametrize("path", SHARED_BVH, ids=lambda p: p.name)
@pytest.mark.parametrize("seed", [0, 1])
def test_renamed_copy_reads_to_the_same_joints(tmp_path: Path, path: Path, seed: int) -> None:
    orig = read_motion(path)[0]
    copy = read_motion(_renamed(path, tmp_path / path.name, seed))[0]
    assert copy.meta["skeleton"] == "auto", copy.meta["joint_map"]
    np.testing.assert_allclose(copy.positions, orig.positions, atol=1e-9)


@requires_shared
def test_smpl_names_of_a_momask_bvh_read_and_inspect_prints_the_map(tmp_path: Path, capsys) -> None:
    from motion2robot.cli import main

    src = MOTIONS / "bvh" / "momask_template_aistpp_gBR.bvh"
    smpl = {"Hips": "Pelvis", "LeftUpLeg": "Left_hip", "LeftLeg": "Left_knee", "LeftFoot": "Left_ankle",
            "LeftToe": "Left_foot", "RightUpLeg": "Right_hip", "RightLeg": "Right_knee",
            "RightFoot": "Right_ankle", "RightToe": "Right_foot", "Spine": "Spine1", "Spine1": "Spine2",
            "Spine2": "Spine3", "LeftShoulder": "Left_collar", "LeftArm": "Left_shoulder",
            "LeftForeArm": "Left_elbow", "LeftHand": "Left_wrist", "RightShoulder": "Right_collar",
            "RightArm": "Right_shoulder", "RightForeArm": "Right_elbow", "RightHand": "Right_wrist"}
    text = re.sub(r"((?:ROOT|JOINT)\s+)(\S+)", lambda m: m.group(1) + smpl.get(m.group(2), m.group(2)),
                  src.read_text())  # one pass: Spine -> Spine1 is not renamed again
    (tmp_path / "m.bvh").write_text(text)
    m = read_motion(tmp_path / "m.bvh")[0]
    np.testing.assert_allclose(m.positions, read_motion(src)[0].positions, atol=1e-9)
    assert main(["inspect", str(tmp_path / "m.bvh")]) == 0
    out = capsys.readouterr().out
    assert "skeleton    auto" in out and "left_shoulder=Left_shoulder" in out and "left_collar=Left_collar" in out


@requires_shared
def test_name_map_still_overrides_the_automatic_map(tmp_path: Path) -> None:
    src = MOTIONS / "bvh" / "momask_template_aistpp_gBR.bvh"
    text = re.sub(r"(JOINT\s+)LeftUpLeg(\s)", r"\g<1>L_Thigh\g<2>", src.read_text())
    (tmp_path / "m.bvh").write_text(text)
    (tmp_path / "map.toml").write_text('[keypoints]\nhead = "Neck"\n')
    m = read_motion(tmp_path / "m.bvh", name_map=tmp_path / "map.toml")[0]
    assert m.meta["skeleton"] == "user+auto" and "head=Neck" in m.meta["joint_map"]
    np.testing.assert_allclose(m.positions[:, 15], m.positions[:, 12], atol=1e-12)  # head on the neck


def test_a_chain_that_does_not_go_down_the_tree_is_not_mapped(tmp_path: Path) -> None:
    names = ["Hips", "LeftUpLeg", "LeftLeg", "LeftFoot"]
    parents = [-1, 0, 0, 0]  # siblings: no chain
    _, missing = auto_map(names, parents, np.ones((4, 3)), [False] * 4)
    assert "left_knee" in missing and "left_ankle" in missing
    with pytest.raises(InputFileError, match="unknown skeleton"):
        choose_map("x.bvh", names, None, (parents, np.ones((4, 3)), [False] * 4))

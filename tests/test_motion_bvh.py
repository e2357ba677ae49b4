"""BVH: Euler composition, units and up-axis detection, name maps, End Sites."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2robot.errors import InputFileError
from motion2robot.motion import KP, read_motion, subject_height
from motion2robot.motion.bvh import forward_kinematics, parse_bvh
from motion2robot.motion.skeletons import PRESETS, choose_map
from tests.test_motion_support import MIXAMO_NAMES, bvh_text, walking_yup, write

TWO_JOINTS = """HIERARCHY
ROOT A
{{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition {order}
  JOINT B
  {{
    OFFSET 0 1 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site #name: C
    {{
      OFFSET 0 0 2
    }}
  }}
}}
MOTION
Frames: 1
Frame Time: 0.05
0 0 0 {angles} 0 0 0
"""


@pytest.mark.parametrize("order,angles,expected_b", [
    # R = Rx(90) Ry(0) Rz(90): (0,1,0) -> Rz -> (-1,0,0) -> Rx -> (-1,0,0)
    ("Xrotation Yrotation Zrotation", "90 0 90", (-1.0, 0.0, 0.0)),
    # R = Rz(90) Ry(0) Rx(90): (0,1,0) -> Rx -> (0,0,1) -> Rz -> (0,0,1)
    ("Zrotation Yrotation Xrotation", "90 0 90", (0.0, 0.0, 1.0)),
    # R = Ry(90) Rx(0) Rz(0): (0,1,0) stays
    ("Yrotation Xrotation Zrotation", "90 0 0", (0.0, 1.0, 0.0)),
])
def test_euler_channels_compose_in_listed_order(tmp_path: Path, order: str, angles: str, expected_b) -> None:
    clip = parse_bvh(write(tmp_path / "two.bvh", TWO_JOINTS.format(order=order, angles=angles)))
    assert clip.skeleton.names == ("A", "B", "C")  # named End Site
    pos = forward_kinematics(clip)
    np.testing.assert_allclose(pos["B"][0], expected_b, atol=1e-12)
    # the End Site inherits B's frame (B's own rotation is zero here): C = B + R_A (0, 0, 2)
    a = [float(v) for v in angles.split()]
    from motion2robot.motion.bvh import _axis_rotations
    ra = np.eye(3)
    for ch, ang in zip(order.split(), a):
        ra = ra @ _axis_rotations(ch[0], np.array([ang]))[0]
    np.testing.assert_allclose(pos["C"][0], np.array(expected_b) + ra @ [0, 0, 2], atol=1e-12)


@pytest.mark.parametrize("scale,units", [(1.0, "m"), (100.0, "cm"), (1 / 0.0254, "inch"),
                                         (1 / (0.0254 / 0.45), "cmu"), (1000.0, "mm")])
def test_units_are_detected_from_skeleton_size(tmp_path: Path, scale: float, units: str) -> None:
    m = read_motion(write(tmp_path / "s.bvh", bvh_text(scale=scale)))[0]
    assert m.meta["units"] == units and "detected" in m.meta["units_source"]
    ref = read_motion(_npy(tmp_path, walking_yup(30, fps=30.0, bob=0.0)), fps=30.0)[0]
    np.testing.assert_allclose(m.positions, ref.positions, atol=1e-4)
    assert m.fps == 30.0


def _npy(tmp_path: Path, arr: np.ndarray) -> Path:
    np.save(tmp_path / "ref.npy", arr)
    return tmp_path / "ref.npy"


def test_units_and_up_overrides(tmp_path: Path) -> None:
    path = write(tmp_path / "s.bvh", bvh_text(scale=100.0))
    m = read_motion(path, units="cm", up="y")[0]
    assert m.meta["units_source"] == "--units" and m.meta["up_axis_source"] == "--up"
    with pytest.raises(InputFileError, match="units"):
        read_motion(path, units="m")  # a 165 m subject
    zpath = write(tmp_path / "z.bvh", bvh_text(scale=100.0, z_up=True))
    mz = read_motion(zpath)[0]
    assert mz.meta["up_axis"] == "z"
    np.testing.assert_allclose(mz.positions, m.positions, atol=1e-6)
    np.testing.assert_allclose(read_motion(zpath, up="z")[0].positions, m.positions, atol=1e-6)


def test_channel_order_of_real_rotation_changes_pose(tmp_path: Path) -> None:
    """Same numbers, different listed order -> different FK (the order is honoured per joint)."""
    a = parse_bvh(write(tmp_path / "a.bvh", TWO_JOINTS.format(order="Xrotation Yrotation Zrotation", angles="30 40 50")))
    b = parse_bvh(write(tmp_path / "b.bvh", TWO_JOINTS.format(order="Zrotation Yrotation Xrotation", angles="30 40 50")))
    assert np.linalg.norm(forward_kinematics(a)["B"] - forward_kinematics(b)["B"]) > 0.1


def test_user_name_map_in_toml(tmp_path: Path) -> None:
    odd = tuple(f"j{i}_{n.lower()}" for i, n in enumerate(MIXAMO_NAMES))
    path = write(tmp_path / "odd.bvh", bvh_text(scale=100.0, names=odd))
    with pytest.raises(InputFileError) as err:
        read_motion(path)
    msg = str(err.value)
    assert "unknown skeleton" in msg and "pelvis" in msg and "--name-map" in msg and "\n" not in msg
    toml = "[keypoints]\n" + "\n".join(f'{kp} = "{odd[i]}"' for i, kp in enumerate(KP))
    toml = toml.replace('spine3 = "j9_spine2"', 'spine3 = ["j6_spine1", "j12_neck"]')  # a midpoint
    m = read_motion(path, name_map=write(tmp_path / "map.toml", toml))[0]
    assert m.meta["skeleton"] == "user"
    sp = m.positions[:, KP["spine3"]]
    mid = (m.positions[:, KP["spine2"]] + m.positions[:, KP["neck"]]) / 2
    np.testing.assert_allclose(sp, mid, atol=1e-9)
    with pytest.raises(InputFileError, match="unknown keypoint"):
        read_motion(path, name_map=write(tmp_path / "bad.toml", 'hips = "j0_hips"\n'))


def test_presets_map_all_keypoints_and_namespaces() -> None:
    for name, m in PRESETS.items():
        assert set(m) == set(KP), name
    names = [f"mixamorig:{n}" for n in MIXAMO_NAMES]
    preset, mapping = choose_map("x.bvh", names)
    assert preset == "mixamo_lafan" and mapping["pelvis"] == ["mixamorig:Hips"]


def test_real_bvh_skeletons_are_recognised() -> None:
    from tests._shared import MOTIONS
    if MOTIONS is None:
        pytest.skip("no shared clips")
    seen = {}
    for f in sorted((MOTIONS / "bvh").glob("*.bvh")):
        m = read_motion(f)[0]
        seen[f.name.split("_")[0]] = (m.meta["skeleton"], m.meta["units"])
        assert 1.4 <= subject_height(m) <= 2.0
    assert seen["bandai"] == ("bandai_namco", "cm")
    assert seen["xia"] == ("cmu", "cmu") and seen["cmu"][1] in ("cmu", "cm")
    assert seen["momask"] == ("mixamo_lafan", "m")
    assert seen["gen"][1] == "m"

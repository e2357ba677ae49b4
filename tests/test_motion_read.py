"""Readers: every real clip in ../shared/motions, the decode-vs-joints check, formats, tensors."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from motion2robot.errors import InputFileError
from motion2robot.motion import KP, detect_format, from_tensor, read_motion, subject_height
from motion2robot.motion.features import decode_positions
from motion2robot.motion.human import HumanMotion
from tests._shared import MOTIONS, requires_shared
from tests._tensor import FakeTensor
from tests.test_motion_support import walking_yup

# Every file of the development set: expected format, clip count, frames of clip 0 -- or the
# reason it is refused (a substring of the one-line error).
EXPECTED = {
    "bvh/bandai_bow_normal_001.bvh": ("bvh", 1, 138),
    "bvh/bandai_byebye_normal_001.bvh": ("bvh", 1, 121),
    "bvh/bandai_dance-short_normal_001.bvh": ("bvh", 1, 1901),
    "bvh/bandai_kick_normal_001.bvh": ("bvh", 1, 358),
    "bvh/bandai_punch_normal_001.bvh": ("bvh", 1, 224),
    "bvh/bandai_run_normal_001.bvh": ("bvh", 1, 24),
    "bvh/bandai_walk-back_normal_001.bvh": ("bvh", 1, 31),
    "bvh/bandai_walk_normal_001.bvh": ("bvh", 1, 195),
    "bvh/cmu_01_01.bvh": ("bvh", 1, 2751),  # frame 0 is a T-pose and is dropped
    "bvh/cmu_cc_002_01_walk.bvh": ("bvh", 1, 171),
    "bvh/cmu_cc_002_04_jump.bvh": ("bvh", 1, 241),
    "bvh/cmu_cc_005_02_dance.bvh": ("bvh", 1, 562),
    "bvh/gen_gmd_ik_anim0.bvh": ("bvh", 1, 120),
    "bvh/gen_mdm_walk_pickup_ik.bvh": ("bvh", 1, 60),
    "bvh/momask_template_aistpp_gBR.bvh": ("bvh", 1, 720),
    "bvh/xia_angry_13_000.bvh": ("bvh", 1, 140),
    "bvh/xia_depressed_18_000.bvh": ("bvh", 1, 105),
    "bvh/xia_neutral_01_000.bvh": ("bvh", 1, 327),
    "bvh/xia_neutral_16_000.bvh": ("bvh", 1, 150),
    "bvh/xia_sexy_01_000.bvh": ("bvh", 1, 258),
    "humanml3d_joints/000021_raw_joints52.npy": ("humanml3d_joints", 1, 180),
    "humanml3d_joints/007005.npy": ("humanml3d_joints", 1, 199),
    "humanml3d_joints/011673.npy": ("humanml3d_joints", 1, 199),
    "humanml3d_joints/012314.npy": ("humanml3d_joints", 1, 170),
    "humanml3d_joints/M010968.npy": ("humanml3d_joints", 1, 70),
    "humanml3d_vecs/007005.npy": ("humanml3d_vecs", 1, 199),
    "humanml3d_vecs/011673.npy": ("humanml3d_vecs", 1, 199),
    "humanml3d_vecs/012314.npy": ("humanml3d_vecs", 1, 170),
    "humanml3d_vecs/M010968.npy": ("humanml3d_vecs", 1, 70),
    "humanml3d_vecs/Mean.npy": "a Mean/Std statistics file, not a motion",
    "humanml3d_vecs/Std.npy": "a Mean/Std statistics file, not a motion",
    "mdm_results/gmd_template_joints.npy": ("mdm_array", 1, 120),
    "mdm_results/mdm_throw_ball_results.npy": ("mdm_results", 30, None),
    "mdm_results/mdm_walk_pickup_results.npy": ("mdm_results", 3, 60),
    "smpl/amass_dmpl_sample.npz": ("amass", 1, 235),  # approximate skeleton (no --body-model): a warning
    "smpl/aistpp_gBR_sBM_cAll_d04_mBR0_ch01.pkl": ("aistpp_smpl", 1, 720),
    "cmu_asf_amc/01.asf": "is an ASF skeleton without motion",  # the skeleton; the take is the .amc
    "cmu_asf_amc/01_01.amc": ("asf_amc", 1, 2751),
}
PAIRED = ("007005", "011673", "012314", "M010968")  # same clip as joints and as 263-d features


def _check_canonical(m: HumanMotion) -> None:
    p = m.positions
    feet = p[:, [KP["left_ankle"], KP["right_ankle"], KP["left_foot"], KP["right_foot"]], 2]
    assert abs(feet.min()) < 1e-9  # floor at z = 0 from the lowest foot point
    assert np.allclose(p[0, KP["pelvis"], :2], 0.0, atol=1e-9)
    left = p[0, KP["left_hip"]] - p[0, KP["right_hip"]] + p[0, KP["left_shoulder"]] - p[0, KP["right_shoulder"]]
    assert abs(left[0]) < 1e-6 and left[1] > 0  # facing +x: left is +y
    assert (p[:, KP["head"], 2] > p[:, KP["pelvis"], 2]).mean() > 0.8  # z up
    hips = p[:, KP["left_hip"], :2] - p[:, KP["right_hip"], :2]
    fwd = np.stack([hips[:, 1], -hips[:, 0]], axis=1)  # per-frame facing = left x up
    toes = p[:, [KP["left_foot"], KP["right_foot"]], :2] - p[:, [KP["left_ankle"], KP["right_ankle"]], :2]
    assert np.median(np.einsum("tfi,ti->tf", toes, fwd)) > 0  # toes point forward: not mirrored


@requires_shared
def test_every_shared_file_is_listed() -> None:
    found = {str(p.relative_to(MOTIONS)) for p in MOTIONS.rglob("*") if p.is_file() and p.suffix != ".md"}
    assert found == set(EXPECTED)


@requires_shared
@pytest.mark.parametrize("rel", sorted(EXPECTED))
def test_shared_file_reads_or_is_refused(rel: str) -> None:
    exp = EXPECTED[rel]
    path = MOTIONS / rel
    if isinstance(exp, str):
        with pytest.raises(InputFileError) as err:
            read_motion(path)
        assert exp in str(err.value) and "\n" not in str(err.value) and str(path) in str(err.value)
        return
    fmt, n, frames = exp
    assert detect_format(path) == fmt
    clips = read_motion(path, clip=None if n < 5 else 0)
    assert len(clips) == (n if n < 5 else 1)
    for m in clips:
        assert m.meta["format"] == fmt and m.meta["source"] == str(path)
        assert 1.4 <= subject_height(m) <= 2.0, subject_height(m)
        assert 0.5 < m.duration < 70 and m.fps in (20.0, 24.0, 30.0, 60.0, 120.0)
        _check_canonical(m)
    if frames is not None:
        assert clips[0].num_frames == frames


@requires_shared
@pytest.mark.parametrize("name", PAIRED)
def test_decoded_features_match_joints_within_1mm(name: str) -> None:
    feat = np.load(MOTIONS / "humanml3d_vecs" / f"{name}.npy")
    joints = np.load(MOTIONS / "humanml3d_joints" / f"{name}.npy")
    assert np.abs(decode_positions(feat) - joints).max() < 1e-3  # measured: <= 2.1e-7 m
    a = read_motion(MOTIONS / "humanml3d_vecs" / f"{name}.npy")[0]
    b = read_motion(MOTIONS / "humanml3d_joints" / f"{name}.npy")[0]
    assert np.abs(a.positions - b.positions).max() < 1e-3
    assert a.contacts is not None and b.contacts is None


@requires_shared
def test_normalised_features_are_denormalised(tmp_path: Path) -> None:
    vecs = MOTIONS / "humanml3d_vecs"
    mean, std = np.load(vecs / "Mean.npy"), np.load(vecs / "Std.npy")
    raw = np.load(vecs / "012314.npy")
    np.save(tmp_path / "norm.npy", ((raw - mean) / std).astype(np.float32))
    with pytest.raises(InputFileError, match="looks like normalised features"):
        read_motion(tmp_path / "norm.npy")
    m = read_motion(tmp_path / "norm.npy", mean=vecs / "Mean.npy", std=vecs / "Std.npy")[0]
    ref = read_motion(vecs / "012314.npy")[0]
    assert "normalised" in m.meta["features"]
    assert np.abs(m.positions - ref.positions).max() < 1e-3
    assert (m.contacts == ref.contacts).all()
    # raw input with statistics given is recognised as raw
    assert read_motion(vecs / "012314.npy", mean=vecs / "Mean.npy", std=vecs / "Std.npy")[0].meta["features"].startswith("raw")


@requires_shared
def test_mdm_results_are_trimmed_with_prompts() -> None:
    path = MOTIONS / "mdm_results" / "mdm_throw_ball_results.npy"
    clips = read_motion(path)
    assert len(clips) == 30
    from motion2robot.motion.safe_pickle import load_npy
    lengths = load_npy(path)["lengths"]
    assert [m.num_frames for m in clips] == [int(n) for n in lengths]
    assert all(m.meta["prompt"] == "A person throws a ball" for m in clips)
    assert [m.meta["clip"] for m in clips] == list(range(30))
    one = read_motion(path, clip=7)
    assert len(one) == 1 and one[0].meta["clip"] == 7 and one[0].num_frames == int(lengths[7])


@requires_shared
def test_generated_bvh_matches_its_mdm_source() -> None:
    """MANIFEST: gen_mdm_walk_pickup_ik.bvh is MDM sample 0 via IK (max 4.8 cm, mean 1.0 cm)."""
    bvh = read_motion(MOTIONS / "bvh" / "gen_mdm_walk_pickup_ik.bvh", fps=20)[0]
    npy = read_motion(MOTIONS / "mdm_results" / "mdm_walk_pickup_results.npy", clip=0)[0]
    err = np.linalg.norm(bvh.positions - npy.positions, axis=-1)
    assert err.mean() < 0.04 and err.max() < 0.10  # measured: mean 3.0 cm, canonical frames aligned independently


def test_joint_batches_folders_and_supersets(tmp_path: Path) -> None:
    one = walking_yup(30)
    np.save(tmp_path / "batch.npy", np.stack([one, one + [0.0, 0.0, 1.0]]).astype(np.float32))
    clips = read_motion(tmp_path / "batch.npy")
    assert len(clips) == 2 and np.allclose(clips[0].positions, clips[1].positions)
    np.save(tmp_path / "smplh.npy", np.concatenate([one, np.zeros((30, 30, 3))], axis=1))
    m = read_motion(tmp_path / "smplh.npy")[0]
    assert "first 22 of 52" in m.meta["note"]
    folder = tmp_path / "clips"
    folder.mkdir()
    for i in range(3):
        np.save(folder / f"{i:03d}.npy", walking_yup(20 + i))
    clips = read_motion(folder)
    assert [c.num_frames for c in clips] == [20, 21, 22] and detect_format(folder) == "humanml3d_joints"
    assert read_motion(folder, clip=2)[0].num_frames == 22


def test_canonical_frame_of_synthetic_walk(tmp_path: Path) -> None:
    np.save(tmp_path / "walk.npy", walking_yup(40, speed=1.0))
    m = read_motion(tmp_path / "walk.npy")[0]
    _check_canonical(m)
    assert m.positions[-1, KP["pelvis"], 0] == pytest.approx(39 / 20.0, abs=1e-6)  # walks along +x
    assert m.meta["up_axis"] == "y" and m.meta["units"] == "m" and m.fps == 20.0


def test_npz_reader_detects_axes_and_units(tmp_path: Path) -> None:
    yup = walking_yup(30)
    zup_cm = np.stack([yup[..., 2], yup[..., 0], yup[..., 1]], axis=-1) * 100.0  # z up, facing +x
    np.savez(tmp_path / "m.npz", joints=zup_cm, fps=30.0)
    assert detect_format(tmp_path / "m.npz") == "npz"
    m = read_motion(tmp_path / "m.npz")[0]
    assert m.meta["up_axis"] == "z" and m.meta["units"] == "cm" and m.fps == 30.0
    _check_canonical(m)
    ref = read_motion(_save(tmp_path / "ref.npy", yup), fps=30.0)[0]
    assert np.abs(m.positions - ref.positions).max() < 1e-9
    np.savez(tmp_path / "nofps.npz", positions=zup_cm)
    with pytest.raises(InputFileError, match="no 'fps'"):
        read_motion(tmp_path / "nofps.npz")


def _save(path: Path, arr: np.ndarray) -> Path:
    np.save(path, arr)
    return path


def test_from_tensor_joints_and_mdm_layout(tmp_path: Path) -> None:
    walk = walking_yup(25)
    t = FakeTensor(walk)
    m = from_tensor(t, layout="humanml3d_joints")[0]
    assert t.calls == ["detach", "cpu"] and m.num_frames == 25
    mdm = from_tensor(FakeTensor(walk.transpose(1, 2, 0)[None]), layout="humanml3d_joints")[0]
    assert np.allclose(mdm.positions, m.positions)
    with pytest.raises(InputFileError, match="unknown layout"):
        from_tensor(t, layout="smpl")


@requires_shared
def test_from_tensor_normalised_features() -> None:
    vecs = MOTIONS / "humanml3d_vecs"
    mean, std, raw = (np.load(vecs / f) for f in ("Mean.npy", "Std.npy", "M010968.npy"))
    m = from_tensor(FakeTensor((raw - mean) / std), layout="humanml3d_vecs", mean=mean, std=std)[0]
    ref = read_motion(vecs / "M010968.npy")[0]
    assert np.abs(m.positions - ref.positions).max() < 1e-3


@pytest.mark.skipif(importlib.util.find_spec("torch") is not None, reason="torch is installed")
def test_pt_without_torch_says_how_to_install(tmp_path: Path) -> None:
    import zipfile
    with zipfile.ZipFile(tmp_path / "m.pt", "w") as z:
        z.writestr("archive/data.pkl", b"\x80\x02}q\x00.")
    assert detect_format(tmp_path / "m.pt") == "pt"
    with pytest.raises(InputFileError, match=r"pip install motion2robot\[torch\]"):
        read_motion(tmp_path / "m.pt")


@pytest.mark.skipif(importlib.util.find_spec("torch") is None, reason="torch is not installed")
def test_pt_with_real_torch(tmp_path: Path) -> None:  # pragma: no cover - needs torch
    import torch
    walk = walking_yup(25)
    torch.save(torch.from_numpy(walk), tmp_path / "m.pt")
    m = read_motion(tmp_path / "m.pt")[0]
    assert m.meta["format"] == "humanml3d_joints" and m.num_frames == 25
    assert np.allclose(from_tensor(torch.from_numpy(walk))[0].positions, m.positions)


def test_format_override(tmp_path: Path) -> None:
    np.save(tmp_path / "x.npy", walking_yup(20).transpose(1, 2, 0)[None])
    assert detect_format(tmp_path / "x.npy") == "mdm_array"
    with pytest.raises(InputFileError, match="not HumanML3D joints"):
        read_motion(tmp_path / "x.npy", format="humanml3d_joints")
    with pytest.raises(InputFileError, match="unknown --format"):
        read_motion(tmp_path / "x.npy", format="fbx")

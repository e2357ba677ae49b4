"""SMPL-family parameters through a body model: a fixture with an SMPL-H model file's key layout."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.motion import read_motion
from motion2robot.motion.body_model import approximate_model, joint_positions, load_body_model
from motion2robot.motion.canonical import canonicalize
from motion2robot.motion.human import SMPL22_PARENTS

#: SMPL-H's 52 joints: the 22 body joints, then 15 left-hand joints under the left wrist (20) and
#: 15 right-hand joints under the right wrist (21), three per finger.
SMPLH_PARENTS = list(SMPL22_PARENTS) + [
    p for wrist, first in ((20, 22), (21, 37)) for f in range(5) for p in (wrist, first + 3 * f, first + 3 * f + 1)]


def smplh_fixture(path: Path, seed: int = 0) -> Path:
    """An SMPL-H-like model .npz (v_template, J_regressor, kintree_table, shapedirs, posedirs,
    weights, f) with small numbers of our own: three vertices around each joint of a plausible rest
    skeleton, J_regressor averaging them, 16 shape directions."""
    rng = np.random.default_rng(seed)
    body = approximate_model().rest + [0.0, 0.9, 0.0]
    hands = np.concatenate([body[w] + [s * 0.03 * (1 + k % 3), 0.0, 0.01 * (k // 3)] for w, s in ((20, 1), (21, -1))
                            for k in range(15)]).reshape(30, 3)
    joints = np.concatenate([body, hands])
    verts = np.repeat(joints, 3, axis=0) + rng.normal(scale=0.01, size=(52 * 3, 3))
    jreg = np.zeros((52, 52 * 3))
    for j in range(52):
        w = rng.uniform(0.2, 1.0, 3)
        jreg[j, 3 * j:3 * j + 3] = w / w.sum()
    kintree = np.stack([np.array([2**32 - 1] + SMPLH_PARENTS[1:], dtype=np.int64), np.arange(52)])
    np.savez(path, v_template=verts, J_regressor=jreg, kintree_table=kintree,
             shapedirs=rng.normal(scale=0.002, size=(52 * 3, 3, 16)), posedirs=np.zeros((52 * 3, 3, 459)),
             weights=np.eye(52).repeat(3, axis=0), f=np.arange(30).reshape(10, 3))
    return path


def _quat_matrix(aa: np.ndarray) -> np.ndarray:
    """Axis-angle -> matrix through a unit quaternion (a different route from Rodrigues)."""
    angle = np.linalg.norm(aa, axis=-1, keepdims=True)
    axis = np.where(angle > 0, aa / np.where(angle > 0, angle, 1), 0)
    w, (x, y, z) = np.cos(angle[..., 0] / 2), np.moveaxis(axis * np.sin(angle / 2), -1, 0)
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
                     np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
                     np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1)], -2)


def _independent_fk(model_path: Path, rot: np.ndarray, trans: np.ndarray, betas=None) -> np.ndarray:
    """Homogeneous 4x4 transforms down the tree, from the raw file: (T, 22, 3)."""
    d = np.load(model_path)
    v = d["v_template"] + (d["shapedirs"][..., :len(betas)] @ betas if betas is not None else 0)
    j = d["J_regressor"] @ v
    t = rot.shape[0]
    world = [None] * 22
    for k in range(22):
        local = np.tile(np.eye(4), (t, 1, 1))
        local[:, :3, :3] = rot[:, k]
        if k == 0:
            local[:, :3, 3] = j[0] + trans
            world[k] = local
        else:
            p = int(d["kintree_table"][0, k])
            local[:, :3, 3] = j[k] - j[p]
            world[k] = world[p] @ local
    return np.stack([w[:, :3, 3] for w in world], axis=1)


def _motion(t: int = 40, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Smooth joint rotations (sinusoids of random phase, up to 0.4 rad at 0.5 Hz at 30 fps) and a
    slow walk along x."""
    rng = np.random.default_rng(seed)
    time = np.arange(t)[:, None, None] / 30.0
    aa = rng.uniform(0.1, 0.4, (1, 22, 3)) * np.sin(2 * np.pi * 0.5 * time + rng.uniform(0, 6.3, (1, 22, 3)))
    aa[:, 0] = [np.pi / 2, 0.0, 0.0]  # SMPL's y-up body stood up in a z-up world
    trans = np.stack([np.linspace(0, 1, t), np.zeros(t), np.full(t, 0.9)], axis=1)
    return aa, trans


def test_fk_matches_an_independent_computation(tmp_path: Path) -> None:
    model_path = smplh_fixture(tmp_path / "SMPLH_NEUTRAL.npz")
    aa, trans = _motion()
    rot = _quat_matrix(aa)
    ours = joint_positions(load_body_model(model_path), rot, trans)
    assert np.abs(ours - _independent_fk(model_path, rot, trans)).max() < 1e-6
    betas = np.linspace(-1, 1, 10)
    shaped = joint_positions(load_body_model(model_path, betas), rot, trans)
    assert np.abs(shaped - _independent_fk(model_path, rot, trans, betas)).max() < 1e-6


def _canon(pos: np.ndarray, fps: float):
    return canonicalize("x", pos, fps, up="z", up_source="", units="m", units_source="").positions


def test_smplh_135_and_amass_go_through_the_model(tmp_path: Path) -> None:
    model_path = smplh_fixture(tmp_path / "model.npz")
    aa, trans = _motion()
    rot = _quat_matrix(aa)
    ref = _canon(_independent_fk(model_path, rot, trans), 30.0)
    f135 = np.concatenate([trans, rot[:, :, :2, :].reshape(len(rot), 132)], axis=1)
    np.save(tmp_path / "edit.npy", f135)
    m = read_motion(tmp_path / "edit.npy", body_model=model_path)[0]
    assert m.meta["format"] == "smplh_135" and m.fps == 30.0 and m.meta["body_model"] == "model.npz"
    assert np.abs(m.positions - ref).max() < 1e-6
    betas = np.linspace(-1, 1, 16)
    poses = np.concatenate([aa.reshape(len(aa), 66), np.zeros((len(aa), 90))], axis=1)
    np.savez(tmp_path / "amass.npz", poses=poses, trans=trans, betas=betas, mocap_framerate=np.float32(120.0),
             gender="neutral")
    a = read_motion(tmp_path / "amass.npz", body_model=model_path)[0]
    assert a.meta["format"] == "amass" and a.fps == 120.0 and "16 betas" in a.meta["body_model"]
    ref_b = _canon(_independent_fk(model_path, rot, trans, betas), 120.0)
    assert np.abs(a.positions - ref_b).max() < 1e-6


def test_editor_result_dict_gives_edited_source_target_with_the_instruction(tmp_path: Path) -> None:
    model_path = smplh_fixture(tmp_path / "model.npz")
    aa, trans = _motion()
    rot = _quat_matrix(aa)
    f135 = np.concatenate([trans, rot[:, :, :2, :].reshape(len(rot), 132)], axis=1)
    res = {"pose": f135, "pose_source": f135[::-1].copy(), "pose_target": f135, "text": "raise the right arm"}
    np.save(tmp_path / "0001.npy", np.array(res, dtype=object), allow_pickle=True)
    clips = read_motion(tmp_path / "0001.npy", body_model=model_path)
    assert [c.meta["role"] for c in clips] == ["edited", "source", "target"]
    assert all(c.meta["prompt"] == "raise the right arm" and c.meta["format"] == "edit_result" for c in clips)
    np.testing.assert_allclose(clips[0].positions, clips[2].positions)
    from motion2robot.batch.work import expand_inputs
    assert len(expand_inputs([tmp_path / "0001.npy"]).items) == 3


def test_without_a_model_a_one_line_warning_or_a_refusal_under_strict(tmp_path: Path, capsys) -> None:
    aa, trans = _motion()
    np.savez(tmp_path / "amass.npz", poses=aa.reshape(len(aa), 66), trans=trans, mocap_framerate=30.0)
    assert main(["inspect", str(tmp_path / "amass.npz")]) == 0
    err = capsys.readouterr().err
    assert err.startswith("motion2robot: warning:") and err.count("\n") == 1 and "approximate skeleton" in err
    assert "cm" in err and "--body-model" in err
    assert main(["inspect", str(tmp_path / "amass.npz"), "--strict"]) == 2
    err = capsys.readouterr().err
    assert "--strict" in err and "--body-model" in err and err.count("\n") == 1


@pytest.mark.parametrize("case", ["missing", "object_npz", "pickle_code", "bad_tree"])
def test_bad_body_model_is_one_line_exit_2(tmp_path: Path, capsys, case: str) -> None:
    model = smplh_fixture(tmp_path / "good.npz")
    d = dict(np.load(model))
    bad = tmp_path / ("bad.pkl" if case == "pickle_code" else "bad.npz")
    if case == "missing":
        del d["J_regressor"]
        np.savez(bad, **d)
    elif case == "object_npz":
        d["J_regressor"] = np.array([{"sparse": 1}], dtype=object)
        np.savez(bad, **d)
    elif case == "pickle_code":
        bad.write_bytes(b"cos\nsystem\n(S'echo pwned'\ntR.")
    else:
        d["kintree_table"] = d["kintree_table"][::-1].copy()
        np.savez(bad, **d)
    aa, trans = _motion()
    np.savez(tmp_path / "amass.npz", poses=aa.reshape(len(aa), 66), trans=trans, mocap_framerate=30.0)
    assert main(["inspect", str(tmp_path / "amass.npz"), "--body-model", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("motion2robot: error:") and err.count("\n") == 1 and str(bad) in err
    assert {"missing": "missing J_regressor", "object_npz": "object arrays (pickled", "pickle_code": "refused",
            "bad_tree": "kintree_table"}[case] in err

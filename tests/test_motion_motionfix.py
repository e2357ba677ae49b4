"""MotionFix/OmniME 207-d features: decoded joints equal the joints they were made from."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.errors import InputFileError
from motion2robot.motion import detect_format, from_tensor, read_motion
from motion2robot.motion.motionfix import GROUPS
from motion2robot.motion.rotations import matrix_from_6d, matrix_to_6d
from tests._shared import MOTIONS, requires_shared
from tests.motionfix_encoder import encode
from tests.test_motion_support import walking_yup


def test_6d_is_the_first_two_rows_and_gram_schmidt_recovers_the_matrix() -> None:
    rng = np.random.default_rng(0)
    q, _ = np.linalg.qr(rng.normal(size=(50, 3, 3)))
    q *= np.sign(np.linalg.det(q))[:, None, None]
    d6 = matrix_to_6d(q)
    assert np.allclose(d6[:, :3], q[:, 0]) and np.allclose(d6[:, 3:], q[:, 1])
    np.testing.assert_allclose(matrix_from_6d(d6 * 3.0), q, atol=1e-12)  # scale-free


def _source(name: str):
    return read_motion(MOTIONS / "humanml3d_joints" / f"{name}.npy")[0]


def _save(path: Path, arr: np.ndarray) -> Path:
    np.save(path, arr)
    return path


@requires_shared
@pytest.mark.parametrize("name", ["007005", "011673", "012314", "M010968"])
def test_207d_from_a_humanml3d_clip_decodes_to_its_joints(tmp_path: Path, name: str) -> None:
    src = _source(name)
    feat = encode(src.positions).astype(np.float32)
    path = _save(tmp_path / "edit.npy", feat)
    assert detect_format(path) == "motionfix_207"
    m = read_motion(path)[0]
    err = np.linalg.norm(m.positions - src.positions, axis=-1).max()
    assert err < 1e-3, err  # float32 file
    assert m.fps == 30.0 and m.meta["up_axis"] == "z" and "raw" in m.meta["features"]


def _stats(feat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    mean, std = feat.mean(axis=0), feat.std(axis=0) + 1e-3
    return mean, std


@requires_shared
@pytest.mark.parametrize("layout", ["flat", "groups"])
def test_normalised_207d_with_its_statistics_decodes_the_same(tmp_path: Path, layout: str) -> None:
    src = _source("012314")
    feat = encode(src.positions)
    mean, std = _stats(feat)
    stats = ({"mean": mean, "std": std} if layout == "flat"
             else {n: {"mean": mean[s], "std": std[s]} for n, s in GROUPS})
    (tmp_path / "stats.pkl").write_bytes(pickle.dumps(stats))
    norm = _save(tmp_path / "norm.npy", (feat - mean) / std)
    m = read_motion(norm, stats=tmp_path / "stats.pkl")[0]
    assert np.linalg.norm(m.positions - src.positions, axis=-1).max() < 1e-6
    assert "normalised" in m.meta["features"]
    t = from_tensor((feat - mean) / std, layout="motionfix_207", mean=mean, std=std)[0]
    np.testing.assert_allclose(t.positions, m.positions, atol=1e-9)
    t2 = from_tensor((feat - mean) / std, layout="motionfix_207", mean=stats)[0]
    np.testing.assert_allclose(t2.positions, m.positions, atol=1e-9)


def test_bad_207d_input_is_one_line_exit_2(tmp_path: Path, capsys) -> None:
    walk = walking_yup(30)
    zup = np.stack([walk[..., 2], walk[..., 0], walk[..., 1]], axis=-1)
    feat = encode(zup)
    wide = _save(tmp_path / "wide.npy", feat[:, :206])
    assert main(["inspect", str(wide), "--format", "motionfix_207"]) == 2
    err = capsys.readouterr().err
    assert "(T, 207)" in err and err.count("\n") == 1
    mean, std = _stats(feat)
    (tmp_path / "short.pkl").write_bytes(pickle.dumps({"mean": mean[:200], "std": std[:200]}))
    norm = _save(tmp_path / "norm.npy", (feat - mean) / std)
    assert main(["inspect", str(norm), "--stats", str(tmp_path / "short.pkl")]) == 2
    err = capsys.readouterr().err
    assert "200 / 200 values" in err and err.count("\n") == 1
    assert main(["inspect", str(norm)]) == 2
    assert "--stats" in capsys.readouterr().err
    (tmp_path / "evil.pkl").write_bytes(b"cos\nsystem\n(S'echo pwned'\ntR.")
    assert main(["inspect", str(norm), "--stats", str(tmp_path / "evil.pkl")]) == 2
    assert "refused" in capsys.readouterr().err
    with pytest.raises(InputFileError, match="statistics of 5 / 5"):
        from_tensor(feat, layout="motionfix_207", mean=mean[:5], std=std[:5])


def test_a_hand_built_feature_sequence_decodes_to_hand_computed_joints() -> None:
    """Three frames written by hand in the reference convention (athn-nik/motionfix, see the module
    docstring): v_i in the previous frame's FULL pelvis rotation, D_i = Rz_{i-1}^T Rz_i, 6D = the
    first two rows, p_rel = Rz_i^T (p - pelvis). Expected joints worked out by hand below."""
    from motion2robot.motion.motionfix import decode_positions

    c30, s30, r2 = np.sqrt(3) / 2, 0.5, np.sqrt(0.5)
    eye6 = [1, 0, 0, 0, 1, 0]
    f = np.zeros((3, 207))
    f[:, 15:141] = np.tile(eye6, 21)  # joint rotations: not used for positions
    for i in range(3):
        f[i, 141 + 3 * 1:141 + 3 * 2] = [0.1, 0.0, -0.1]  # left hip, heading frame
        f[i, 141 + 3 * 15:141 + 3 * 16] = [0.0, 0.0, 0.5]  # head
    # frame 0: v = 0, Rxy = I, D = I
    f[0, 3:9], f[0, 9:15] = eye6, eye6
    # frame 1: v = (0.2, 0, 0) in R_0 = I; D = Rz(90 deg) (rows (0,-1,0), (1,0,0)); Rxy = Rx(30 deg)
    f[1, 0:3], f[1, 9:15], f[1, 3:9] = [0.2, 0, 0], [0, -1, 0, 1, 0, 0], [1, 0, 0, 0, c30, -s30]
    # frame 2: v = (0, 0.2, 0) in R_1 = Rz(90) Rx(30); D = Rz(-45 deg) (rows (c, s, 0), (-s, c, 0)); Rxy = I
    f[2, 0:3], f[2, 9:15], f[2, 3:9] = [0, 0.2, 0], [r2, r2, 0, -r2, r2, 0], eye6
    p = decode_positions(f)
    # t_0 = 0; t_1 = I (0.2, 0, 0); t_2 = t_1 + Rz90 Rx30 (0, 0.2, 0) = t_1 + Rz90 (0, 0.2 c30, 0.2 s30)
    #     = (0.2, 0, 0) + (-0.2 c30, 0, 0.1)
    t2 = np.array([0.2 - 0.2 * c30, 0.0, 0.1])
    np.testing.assert_allclose(p[:, 0], [[0, 0, 0], [0.2, 0, 0], t2], atol=1e-12)
    # left hip: t + Rz_i (0.1, 0, -0.1) with Rz_0 = I, Rz_1 = Rz(90): (0, 0.1, -0.1), Rz_2 = Rz(45)
    np.testing.assert_allclose(p[:, 1], [[0.1, 0, -0.1], [0.2, 0.1, -0.1], t2 + [0.1 * r2, 0.1 * r2, -0.1]],
                               atol=1e-12)
    # head: straight above the pelvis whatever the heading (the tilt Rxy does not enter p_rel)
    np.testing.assert_allclose(p[:, 15], p[:, 0] + [0, 0, 0.5], atol=1e-12)


@requires_shared
@pytest.mark.parametrize("k, eps, word", [(2.0, 1e-5, "model's standardisation"), (1.0, 1e-5, "data module's")])
def test_features_normalised_as_the_motionfix_code_does_decode_the_same(tmp_path: Path, k, eps, word) -> None:
    """The statistics file in the layout of MotionFix's deps/stats/statistics_motionfix.npy (a dict
    per group of float32 mean/std/min/max, plus body_transl; constant features have std 0), and
    features normalised as its model ((x - mean) / (2 (std + 1e-5))) or data module do."""
    src = _source("012314")
    feat = encode(src.positions)
    mean, std = feat.mean(axis=0), feat.std(axis=0)
    std[np.abs(std) < 1e-9] = 0.0
    assert (std == 0).any()  # e.g. the third entries of the heading deltas' rows
    stats = {n: {"mean": mean[s].astype(np.float32), "std": std[s].astype(np.float32),
                 "min": feat[:, s].min(0).astype(np.float32), "max": feat[:, s].max(0).astype(np.float32)}
             for n, s in GROUPS}
    stats["body_transl"] = {"mean": np.zeros(3, np.float32), "std": np.ones(3, np.float32)}
    np.save(tmp_path / "statistics_motionfix.npy", np.array(stats, dtype=object), allow_pickle=True)
    norm = _save(tmp_path / "out.npy", ((feat - mean) / (k * (std.astype(np.float32) + eps))).astype(np.float32))
    m = read_motion(norm, stats=tmp_path / "statistics_motionfix.npy")[0]
    assert np.linalg.norm(m.positions - src.positions, axis=-1).max() < 1e-3  # float32 statistics and file
    assert word in m.meta["features"]


def test_zero_6d_rotations_are_one_line_exit_2_without_warnings(tmp_path: Path, capsys) -> None:
    np.save(tmp_path / "zeros.npy", np.zeros((30, 135)))  # no rotation can be recovered from a zero 6D row
    with __import__("warnings").catch_warnings():
        __import__("warnings").simplefilter("error")  # a RuntimeWarning would print lines before the error
        assert main(["inspect", str(tmp_path / "zeros.npy"), "--format", "smplh_135"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "NaN/inf" in err

"""Padding read without its length: refused per sample, in every array reader, with the fix; read
with the lengths a batch file carries (MDM's results, an .npz), each sample cut to its own."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.errors import InputFileError
from motion2robot.motion import read_motion
from motion2robot.motion.checks import trailing_zero_frames
from tests._shared import MOTIONS, requires_shared
from tests.test_motion_support import walking_yup


def _padded_joints(tmp_path: Path) -> Path:
    batch = np.stack([walking_yup(40), walking_yup(40)])
    batch[1, 25:] = 0.0
    np.save(tmp_path / "batch.npy", batch)
    return tmp_path / "batch.npy"


def test_trailing_zero_frames_counts_only_the_end() -> None:
    a = walking_yup(10)
    assert trailing_zero_frames(a) == 0
    a[2] = 0.0  # a zero frame inside is no padding (and no body either: the NaN-like checks keep it)
    assert trailing_zero_frames(a) == 0
    a[7:] = 0.0
    assert trailing_zero_frames(a) == 3 and trailing_zero_frames(np.zeros((4, 22, 3))) == 4


def test_a_padded_sample_is_refused_the_others_read(tmp_path: Path) -> None:
    path = _padded_joints(tmp_path)
    assert read_motion(path, clip=0)[0].num_frames == 40
    with pytest.raises(InputFileError, match=r"15 all-zero frames \(frames 25-39 of 40\).*lengths=\(N,\)"):
        read_motion(path, clip=1)
    with pytest.raises(InputFileError, match="all-zero frames"):
        read_motion(path)  # the whole file: the padded sample is named


def test_the_cli_says_it_in_one_line(tmp_path: Path, capsys) -> None:
    np.save(tmp_path / "zeros.npy", np.zeros((30, 22, 3)))
    assert main(["inspect", str(tmp_path / "zeros.npy")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "all zero in every one of its 30 frames" in err[0]


def test_npz_lengths_cut_each_sample(tmp_path: Path) -> None:
    batch = np.load(_padded_joints(tmp_path))
    np.savez(tmp_path / "b.npz", joints=batch, lengths=np.array([40, 25]), fps=20.0)
    clips = read_motion(tmp_path / "b.npz", up="y", units="m")
    assert [c.num_frames for c in clips] == [40, 25]
    np.savez(tmp_path / "bad.npz", joints=batch, lengths=np.array([40, 45]), fps=20.0)
    with pytest.raises(InputFileError, match=r"lengths exceed the motion array \(40 frames\).*\[1\].*45"):
        read_motion(tmp_path / "bad.npz")
    np.savez(tmp_path / "few.npz", joints=batch, lengths=np.array([40]), fps=20.0)
    with pytest.raises(InputFileError, match="2 motions but 1 lengths"):
        read_motion(tmp_path / "few.npz")


@requires_shared
def test_feature_batches_padding_and_nan_are_per_sample(tmp_path: Path) -> None:
    feats = np.load(MOTIONS / "humanml3d_vecs/M010968.npy")[:50]
    alone = read_motion(_save(tmp_path / "one.npy", feats))[0]
    batch = np.stack([feats, feats, feats])
    batch[1, 35:] = 0.0  # padding
    batch[2, 5, 10] = np.nan
    path = _save(tmp_path / "three.npy", batch)
    first = read_motion(path, clip=0)[0]
    # the bad samples decide nothing for the good one (raw or normalised is judged on valid frames)
    assert first.meta["features"] == alone.meta["features"] and np.allclose(first.positions, alone.positions)
    with pytest.raises(InputFileError, match="features end with 15 all-zero frames"):
        read_motion(path, clip=1)
    with pytest.raises(InputFileError, match="NaN/inf"):
        read_motion(path, clip=2)


@requires_shared
def test_mdm_feature_results_are_cut_at_their_lengths(tmp_path: Path) -> None:
    feats = np.load(MOTIONS / "humanml3d_vecs/M010968.npy")[:50]
    motion = np.stack([feats, feats]).transpose(0, 2, 1)[:, :, None, :]  # (N, 263, 1, T)
    motion[1, :, :, 30:] = 0.0
    d = {"motion": motion, "text": ["a", "b"], "lengths": np.array([50, 30])}
    np.save(tmp_path / "results.npy", np.array(d, dtype=object), allow_pickle=True)
    clips = read_motion(tmp_path / "results.npy")
    assert [c.num_frames for c in clips] == [50, 30]
    assert np.allclose(clips[1].positions, clips[0].positions[:30])


def _save(path: Path, arr: np.ndarray) -> Path:
    np.save(path, arr)
    return path

"""Generators' file conventions: (1,T,22,3), (S,R,T,22,3), prompt .txt beside a .npy, MoMask folders."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2robot.batch.work import expand_inputs
from motion2robot.motion import detect_format, read_motion
from tests.test_motion_support import walking_yup


def test_motiongpt_leading_batch_axis_of_one(tmp_path: Path) -> None:
    walk = walking_yup(40)
    np.save(tmp_path / "0_out.npy", walk[None])
    (tmp_path / "0_out.txt").write_text("a person walks forward\n")
    clips = read_motion(tmp_path / "0_out.npy")
    ref = read_motion(_save(tmp_path / "ref.npy", walk))[0]
    assert len(clips) == 1 and np.allclose(clips[0].positions, ref.positions)
    assert clips[0].meta["prompt"] == "a person walks forward" and ref.meta.get("prompt") is None


def _save(path: Path, arr: np.ndarray) -> Path:
    np.save(path, arr)
    return path


def test_mld_all_in_one_samples_times_repetitions(tmp_path: Path) -> None:
    s, r = 2, 3
    arr = np.stack([np.stack([walking_yup(30) + [0.1 * (i * r + j), 0, 0] for j in range(r)]) for i in range(s)])
    path = _save(tmp_path / "all.npy", arr.astype(np.float32))
    (tmp_path / "all.txt").write_text("wave\njump\n")
    assert detect_format(path) == "humanml3d_joints"
    clips = read_motion(path)
    assert len(clips) == s * r
    assert [(c.meta["sample"], c.meta["repetition"]) for c in clips] == [(i, j) for i in range(s) for j in range(r)]
    assert [c.meta["prompt"] for c in clips] == ["wave"] * 3 + ["jump"] * 3
    assert read_motion(path, clip=4)[0].meta["repetition"] == 1
    assert len(expand_inputs([path]).items) == s * r


def test_mld_sample_with_its_prompt_file(tmp_path: Path) -> None:
    path = _save(tmp_path / "t2m_60_batch0_3.npy", walking_yup(60))
    (tmp_path / "t2m_60_batch0_3.txt").write_text("a person walks\nin a circle\n")
    assert read_motion(path)[0].meta["prompt"] == "a person walks in a circle"


def test_momask_output_folder_is_one_item_per_sample(tmp_path: Path) -> None:
    out = tmp_path / "momask_out"
    for k in range(2):
        j, a = out / "joints" / str(k), out / "animations" / str(k)
        j.mkdir(parents=True)
        a.mkdir(parents=True)
        for r in range(2):
            stem = f"sample{k}_repeat{r}_len60"
            np.save(j / f"{stem}.npy", walking_yup(60))
            np.save(j / f"{stem}_ik.npy", walking_yup(60))
            (a / f"{stem}.bvh").write_text("HIERARCHY\n")
            (a / f"{stem}_ik.bvh").write_text("HIERARCHY\n")
    exp = expand_inputs([out])
    kept = sorted(Path(i.path).relative_to(out).as_posix() for i in exp.items)
    assert kept == [f"joints/{k}/sample{k}_repeat{r}_len60_ik.npy" for k in range(2) for r in range(2)]
    assert len(exp.skipped) == 12 and all("MoMask copy" in why for _, why in exp.skipped)
    # named explicitly, a copy is still processed
    assert len(expand_inputs([out / "joints" / "0" / "sample0_repeat0_len60.npy"]).items) == 1

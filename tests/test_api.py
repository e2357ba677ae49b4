"""The in-process API (motion2robot.api): tensors in, records and robot motions out, no files."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motion2robot import api
from motion2robot.errors import MotionBatchError, RobotConfigError, UserError
from motion2robot.motion.checks import trailing_zero_frames
from motion2robot.robot_motion import RobotMotion
from motion2robot.score.batch_input import to_clips
from motion2robot.score.figures import TIMING
from tests._shared import MOTIONS, requires_shared
from tests._tensor import FakeTensor  # the tests' duck-typed torch tensor


def _joints() -> np.ndarray:
    assert MOTIONS is not None
    return np.load(MOTIONS / "humanml3d_joints/M010968.npy")  # (70, 22, 3), y up, 20 fps: an arm raised


def _padded(n: int = 2, frames: tuple[int, ...] = (40, 30), total: int = 48) -> np.ndarray:
    raw = _joints()
    out = np.zeros((n, total, 22, 3), np.float32)
    for b, t in enumerate(frames):
        out[b, :t] = raw[:t]
    return out


def test_padding_without_lengths_bad_lengths_and_shapes() -> None:
    x = np.random.default_rng(0).normal(size=(3, 20, 22, 3))
    x[1, 15:] = 0.0
    assert trailing_zero_frames(x[1]) == 5 and trailing_zero_frames(x[0]) == 0
    with pytest.raises(MotionBatchError, match="sample 1 ends with 5 all-zero frames.*lengths="):
        to_clips(FakeTensor(x))
    for lengths, words in (([20, 15], "one integer per sample"), ([20, 15, 21], "outside 1..20"),
                           ([20, 0, 20], "outside"), ([20, 15.5, 3], "whole numbers")):
        with pytest.raises(MotionBatchError, match=words):
            to_clips(x, lengths=lengths)
    with pytest.raises(MotionBatchError, match=r"expected \(B, T, 22, 3\)"):
        to_clips(np.zeros((2, 10, 21, 3)))
    err = MotionBatchError("x")
    assert isinstance(err, UserError) and isinstance(err, ValueError)
    with pytest.raises(MotionBatchError, match="list of samples carries its own lengths"):
        to_clips([x[0], x[1]], lengths=[20, 15])


@requires_shared
def test_tensor_layouts_give_the_same_clips() -> None:
    raw = _joints()
    vecs = MOTIONS / "humanml3d_vecs"
    mean, std, feat = (np.load(vecs / f) for f in ("Mean.npy", "Std.npy", "M010968.npy"))
    t = FakeTensor(_padded())
    joints = to_clips(t, lengths=FakeTensor(np.array([40, 30])))
    assert t.calls == ["detach", "cpu"] and [c.num_frames for c in joints] == [40, 30]
    mdm = to_clips(_padded().transpose(0, 2, 3, 1), lengths=[40, 30])  # MDM's (B, 22, 3, T)
    single = to_clips(raw[:40])[0]
    listed = to_clips([raw[:40], raw[:30]])
    feats = to_clips(FakeTensor(((feat - mean) / std)[None]), mean=mean, std=std)[0]
    for c in (mdm[0], single, listed[0]):
        assert np.allclose(c.positions, joints[0].positions)
    assert np.abs(feats.positions[:40] - joints[0].positions).max() < 1e-3
    nan = _padded()
    nan[1, 3, 5, 1] = np.nan
    out = to_clips(nan, lengths=[40, 30])
    assert not isinstance(out[0], str) and out[1] == ("input: sample 1 has NaN/inf in frames 3; fix or drop that "
                                                     "sample")


@requires_shared
def test_score_in_process_records_motions_no_files(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    batch = _padded(3, (40, 30, 40))
    batch[2, 10, 0, 0] = np.nan
    result = api.score(FakeTensor(batch), lengths=[40, 30, 40], physics=False, jobs=0)
    assert list(tmp_path.iterdir()) == []  # nothing written
    a, b, bad = result.samples
    assert bad.error.startswith("input: sample 2 has NaN") and bad.motion is None and not bad.executable
    for s, frames in ((a, 40), (b, 30)):
        assert s.error is None and isinstance(s.motion, RobotMotion) and s.record["frames"] == frames
        assert s.motion.num_frames == round((frames - 1) * s.record["figures"]["tempo"]) + 1
        assert s.record["key"] == f"<tensor>#{s.index}" and s.record["fidelity"]["contact_agreement"] > 0.9
    f = result.figures
    assert (f.samples, f.errors, f.executable + f.not_executable) == (3, 1, 2)
    assert result.table().splitlines()[3].split()[:2] == ["samples", "3"]
    assert json.dumps(result.records)  # plain JSON, like the batch rows


@requires_shared
def test_api_figures_equal_the_cli_and_workers_are_reused(tmp_path: Path, capsys) -> None:
    """The default (worker processes) path gives the CLI's figures on the same samples, and a
    second call reuses the workers (same pids)."""
    from motion2robot.cli import main

    raw = _joints()
    batch = np.stack([raw[:40], raw[20:60]])
    np.save(tmp_path / "two.npy", batch)
    assert main(["score", f"two={tmp_path / 'two.npy'}", "--out", str(tmp_path / "o"), "-q", "--no-physics",
                 "-j", "2"]) == 0
    capsys.readouterr()
    cli = json.loads((tmp_path / "o" / "score.json").read_text())["sets"][0]
    from motion2robot.score import pool

    try:
        first = api.score(batch, name="two", physics=False)
        executor = pool._POOL.executor
        again = api.retarget_many(batch[:1], physics=False)
        assert pool._POOL.executor is executor  # the same pool served the second call
        workers = set(executor._processes)  # noqa: SLF001 - the pool's worker pids
    finally:
        api.close()
    mine = first.figures.to_dict()
    assert {k: v for k, v in mine.items() if k not in TIMING} == {k: v for k, v in cli.items() if k not in TIMING}
    assert np.allclose(first.samples[0].motion.qpos, again[0].motion.qpos)
    pids = {s.record["worker"]["pid"] for s in [*first.samples, *again]}
    assert os.getpid() not in pids and pids <= workers  # which worker takes a sample is up to the pool


def test_unknown_robot_and_bad_options() -> None:
    x = np.zeros((1, 5, 22, 3))
    with pytest.raises(RobotConfigError):
        api.score(x, robot="nosuchbot")
    with pytest.raises(UserError, match="legs"):
        api.retarget_many(x, legs="three")


def test_core_never_imports_torch() -> None:
    code = ("import sys, numpy as np, motion2robot.api as a\n"
            "from motion2robot.score.batch_input import to_clips\n"
            "to_clips(np.random.default_rng(0).normal(size=(1, 8, 22, 3)))\n"
            "assert 'torch' not in sys.modules, 'torch imported'\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr

"""The tensor paths with real torch: skipped where torch is not installed (CI, the default
``[test]`` extra). Run with ``pip install "motion2robot[torch]"`` and ``pytest tests/test_torch_real.py``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from motion2robot import api  # noqa: E402
from motion2robot.cli import main  # noqa: E402
from motion2robot.motion import read_motion  # noqa: E402
from motion2robot.motion.tensors import from_tensor, to_numpy  # noqa: E402
from motion2robot.score.batch_input import to_clips  # noqa: E402
from tests._shared import MOTIONS, requires_shared  # noqa: E402

pytestmark = requires_shared


def _joints() -> np.ndarray:
    assert MOTIONS is not None
    return np.load(MOTIONS / "humanml3d_joints/M010968.npy")  # (70, 22, 3), y up, 20 fps


def test_tensors_with_grad_and_low_precision_convert_like_numpy() -> None:
    raw = _joints()[:40]
    for dtype in (torch.float32, torch.float16, torch.bfloat16, torch.float64):
        t = torch.from_numpy(raw).to(dtype).requires_grad_() * 1.0  # a non-leaf tensor with grad
        arr = to_numpy(t)
        assert arr.shape == raw.shape and arr.dtype != object
        tol = {torch.bfloat16: 2e-2, torch.float16: 2e-3}.get(dtype, 1e-6)
        assert np.abs(arr.astype(np.float64) - raw).max() <= tol * max(1.0, np.abs(raw).max())
    clips = from_tensor(torch.from_numpy(raw))
    assert len(clips) == 1 and np.allclose(clips[0].positions, read_motion_joints(raw))


def read_motion_joints(raw: np.ndarray) -> np.ndarray:
    """The canonical positions the numpy path gives for the same joints."""
    return to_clips(raw)[0].positions


def test_padded_batches_with_tensor_lengths_and_the_263_layout() -> None:
    raw = _joints()
    batch = torch.zeros(2, 48, 22, 3)
    batch[0, :40] = torch.from_numpy(raw[:40])
    batch[1, :30] = torch.from_numpy(raw[:30])
    clips = to_clips(batch.requires_grad_(), lengths=torch.tensor([40, 30]))
    assert [c.num_frames for c in clips] == [40, 30]
    assert np.allclose(clips[0].positions, to_clips(raw[:40])[0].positions)
    vecs = MOTIONS / "humanml3d_vecs"
    mean, std, feat = (np.load(vecs / f) for f in ("Mean.npy", "Std.npy", "M010968.npy"))
    norm = torch.from_numpy(((feat - mean) / std)[None].astype(np.float32))
    out = to_clips(norm, mean=torch.from_numpy(mean), std=torch.from_numpy(std))[0]
    plain = to_clips(feat[None])[0]
    assert np.abs(out.positions - plain.positions).max() < 1e-3


def test_pt_files_are_read_with_weights_only(tmp_path: Path, capsys) -> None:
    raw = _joints()
    torch.save(torch.from_numpy(raw), tmp_path / "a.pt")
    torch.save({"motion": torch.from_numpy(raw[None]), "text": ["a person raises an arm"]}, tmp_path / "b.pt")
    a = read_motion(tmp_path / "a.pt")[0]
    b = read_motion(tmp_path / "b.pt")[0]
    assert a.num_frames == b.num_frames == raw.shape[0] and np.allclose(a.positions, b.positions)
    assert np.allclose(a.positions, to_clips(raw)[0].positions)
    torch.save(torch.from_numpy(raw).to(torch.bfloat16), tmp_path / "half.pt")  # numpy has no bfloat16
    assert np.abs(read_motion(tmp_path / "half.pt")[0].positions - a.positions).max() < 0.02

    (tmp_path / "evil.pt").write_bytes(_pickled_object_pt(tmp_path))
    assert main(["inspect", str(tmp_path / "evil.pt")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("motion2robot: error:") and "evil.pt" in err[0]
    assert "posix.system" in err[0] and "weights_only" not in err[0]  # no advice to load it unsafely
    assert not (tmp_path / "pwned").exists()  # the payload never ran


def _pickled_object_pt(tmp_path: Path) -> bytes:
    """A .pt whose pickle names a class outside torch's weights_only allow-list (os.system), made
    in a child process so nothing here can run it."""
    code = ("import os, torch, sys\n"
            "class E:\n"
            "    def __reduce__(self):\n"
            "        return (os.system, ('echo pwned > ' + sys.argv[1],))\n"
            "torch.save({'motion': E()}, sys.argv[2])\n")
    out = tmp_path / "made.pt"
    subprocess.run([sys.executable, "-c", code, str(tmp_path / "pwned"), str(out)], check=True, timeout=120)
    return out.read_bytes()


def test_score_and_project_take_torch_tensors_in_process() -> None:
    raw = _joints()[:40]
    t = torch.from_numpy(raw).requires_grad_() * 1.0
    from_torch = api.score(t[None], physics=False, jobs=0)
    from_numpy = api.score(raw[None], physics=False, jobs=0)
    a, b = from_torch.samples[0], from_numpy.samples[0]
    assert a.error is None and np.allclose(a.motion.qpos, b.motion.qpos)
    p = api.project(t)
    assert p.human.positions.shape == (40, 22, 3) and np.isfinite(p.human.positions).all()

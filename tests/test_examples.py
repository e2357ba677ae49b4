"""The examples/ scripts run as documented in examples/README.md (short settings)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def test_sampling_loop_projects_and_continues_from_the_robots_version(tmp_path: Path) -> None:
    out = tmp_path / "sample.npy"
    run = subprocess.run([sys.executable, str(ROOT / "examples" / "sampling_loop.py"), "--steps", "3", "--every", "2",
                          "--frames", "40", "--out", str(out)], capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    projected = [ln for ln in lines if "projected in" in ln]
    assert len(projected) == 2 and all("op3:" in ln and "executable" in ln for ln in projected)  # steps 2 and 3
    assert any("moved most:" in ln and "rad RMS" in ln for ln in lines)
    final = np.load(out)
    clean = np.load(ROOT / "motion2robot" / "data" / "demo_wave_squat.npy")[:40]
    assert final.shape == clean.shape and np.isfinite(final).all()
    # the last step was a projection: the sample is the robot's version, centimetres from the clip, y up
    d = np.linalg.norm(final - clean, axis=-1).mean()
    assert 0.005 < d < 0.3
    assert abs(np.median(final[:, 15, 1]) - np.median(clean[:, 15, 1])) < 0.3  # the head stays up (y)

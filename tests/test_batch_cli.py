"""``motion2robot batch`` end to end on real clips: rows, resume, bad files, SIGKILL mid-run."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from motion2robot.batch.results import read_rows
from motion2robot.cli import main
from motion2robot.robot_motion import RobotMotion
from tests._shared import MOTIONS, requires_shared

REPO = Path(__file__).resolve().parents[1]
pytestmark = requires_shared


def _clips(folder: Path, n: int, frames: int = 30) -> list[Path]:
    """n short HumanML3D joint clips (y up, 20 fps): crops of a real HumanML3D clip."""
    src = np.load(MOTIONS / "humanml3d_joints" / "007005.npy")
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for k in range(n):
        start = (7 * k) % (len(src) - frames)
        crop = src[start:start + frames].copy()
        crop[..., 1] -= crop[:, [7, 8, 10, 11], 1].min()  # floor at y = 0, as HumanML3D stores clips
        p = folder / f"clip_{k:02d}.npy"
        np.save(p, crop)
        paths.append(p)
    return paths


def _lines(path: Path) -> list[dict]:
    return [json.loads(x) for x in path.read_text().splitlines()]


def test_batch_writes_one_row_per_clip_and_resumes(tmp_path, capsys):
    data = tmp_path / "data"
    _clips(data, 3)
    (data / "empty.npy").write_bytes(b"")  # a bad file: an error row, not a crash
    np.save(data / "Mean.npy", np.zeros(263))  # statistics beside features: skipped
    out, motions = tmp_path / "r.jsonl", tmp_path / "robot"
    args = ["batch", str(data), "--robot", "op3", "--out", str(out), "--no-physics", "--jobs", "2", "-q",
            "--save-motions", str(motions)]
    assert main(args) == 0
    captured = capsys.readouterr()
    assert "4 clips in 4 files; 1 non-motion files skipped (Mean.npy); 4 to do" in captured.err
    rows = {Path(r["path"]).name: r for r in _lines(out)}
    assert sorted(rows) == ["clip_00.npy", "clip_01.npy", "clip_02.npy", "empty.npy"]
    assert rows["empty.npy"]["error"].startswith("read: ") and "empty" in rows["empty.npy"]["error"]
    for name in ("clip_00.npy", "clip_01.npy", "clip_02.npy"):
        r = rows[name]
        assert r["error"] is None, r["error"]
        assert r["frames"] == 30 and r["fps"] == 20.0 and isinstance(r["feasible"], bool)
        assert r["feasible"] == (not r["failed_checks"]) and "rollout" not in r["failed_checks"]
        assert r["timings"]["retarget_s"] > 0 and r["robot"] == "op3"
        saved = RobotMotion.load(r["motion_file"])
        assert saved.num_frames == 30 and saved.robot == "op3"
    assert "4 clips (90 frames) on op3" in captured.out
    assert main(args) == 0  # resume: nothing left to do
    assert "4 already in" in capsys.readouterr().err and len(_lines(out)) == 4
    assert main(args + ["--redo-errors"]) == 0
    assert len(_lines(out)) == 4 and "1 old rows removed" in capsys.readouterr().err


def test_check_thresholds_reach_the_batch_workers(tmp_path, capsys, monkeypatch):
    """The flags of ``check`` given to ``batch`` end up in the CheckOptions its workers judge with."""
    import motion2robot.batch as batch
    from motion2robot.batch.feasibility import FeasibilityJob

    data = tmp_path / "data"
    _clips(data, 1)
    seen = []
    monkeypatch.setattr(batch, "run_plan", lambda plan, config, **kw: seen.append(config))
    args = ["batch", str(data), "--robot", "op3", "--out", str(tmp_path / "r.jsonl"), "-q",
            "--slip-speed", "0.05", "--swing-clearance", "0.004", "--stream-rate", "50", "--sag-compensation"]
    assert main(args) == 0
    capsys.readouterr()
    opts = FeasibilityJob.setup(seen[0]).check_options
    assert (opts.slip_speed, opts.swing_clearance, opts.stream_rate, opts.sag_compensation) == (0.05, 0.004, 50.0, True)
    assert opts.touch_height == 0.002 and opts.physics  # flags not given keep their defaults


def test_unknown_robot_stops_before_any_work(tmp_path, capsys):
    _clips(tmp_path / "d", 1)
    assert main(["batch", str(tmp_path / "d"), "--robot", "no_such_robot", "--out", str(tmp_path / "r.jsonl")]) == 2
    assert not (tmp_path / "r.jsonl").exists()


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie is dead for our purpose
        return Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False


def test_sigkill_mid_run_then_resume_gives_each_clip_exactly_one_line(tmp_path):
    n = 14
    paths = _clips(tmp_path / "data", n, frames=40)
    out = tmp_path / "r.jsonl"
    cmd = [sys.executable, "-m", "motion2robot", "batch", str(tmp_path / "data"), "--robot", "op3",
           "--out", str(out), "--no-physics", "--jobs", "1", "-q"]
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
    try:
        deadline = time.monotonic() + 300  # a cold casadi cache compiles C first
        while time.monotonic() < deadline and proc.poll() is None:
            if out.exists() and out.read_bytes().count(b"\n") >= 3:
                break
            time.sleep(0.01)
        assert proc.poll() is None, f"batch ended before it could be killed: {proc.stderr.read().decode()[-500:]}"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.stderr.close()
    before = _lines(out)
    assert 3 <= len(before) < n
    # The killed driver's worker notices and exits by itself (no orphans left computing).
    pids = {r["worker"]["pid"] for r in before}
    deadline = time.monotonic() + 10
    while any(_alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not any(_alive(p) for p in pids)
    # A crash in the middle of a write leaves a torn last line: simulate one on top of the kill.
    text = out.read_text()
    last = text.splitlines()[-1]
    out.write_text(text[: -len(last) - 1] + last[: len(last) // 2])
    assert len(read_rows(out).rows) == len(before) - 1 and read_rows(out).bad_lines == (len(before),)

    done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-800:]
    assert f"{len(before) - 1} already in" in done.stderr
    rows = _lines(out)  # every line parses
    keys = [r["key"] for r in rows]
    assert sorted(keys) == sorted(f"{p.resolve()}#0" for p in paths)  # each clip exactly once
    assert all(r["error"] is None for r in rows), [r["error"] for r in rows if r["error"]][:2]

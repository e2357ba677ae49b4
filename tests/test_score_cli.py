"""``motion2robot score``: two sets of real clips, figures equal to batch-report's, resume,
determinism, bad input, a killed run resumed without loss."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.score.figures import TIMING
from tests._shared import MOTIONS, requires_shared

#: Short clips: captured (a 31-frame walk backwards) and generated (MDM's three 60-frame samples).
CAPTURED = ("bvh/bandai_walk-back_normal_001.bvh",)
GENERATED = "mdm_results/mdm_walk_pickup_results.npy"
FAST = ["-q", "--no-physics", "-j", "2"]


def _manifest(path: Path, files: list[str]) -> Path:
    path.write_text("".join(f"{MOTIONS / f}\n" for f in files), encoding="utf-8")
    return path


def _score(capsys, *args: str) -> tuple[int, str, str]:
    code = main(["score", *args])
    out = capsys.readouterr()
    return code, out.out, out.err


def _figures(out: Path) -> dict:
    return {s["name"]: s for s in json.loads((out / "score.json").read_text())["sets"]}


def _without_timing(figs: dict) -> dict:
    return {n: {k: v for k, v in s.items() if k not in TIMING} for n, s in figs.items()}


@requires_shared
def test_manifest_split_is_the_manifests() -> None:
    """The sets of these tests are generated / captured as MANIFEST.md says."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    try:
        from manifest_sets import classify
    finally:
        sys.path.pop(0)
    generated, captured = classify(MOTIONS / "MANIFEST.md")
    assert GENERATED in generated and "bvh/gen_gmd_ik_anim0.bvh" in generated
    assert set(CAPTURED) <= set(captured) and not set(generated) & set(captured)
    assert len(generated) + len(captured) == 35  # 38 files less Mean.npy, Std.npy and the ASF skeleton


@requires_shared
def test_two_sets_table_files_and_batch_report_figures(tmp_path: Path, capsys) -> None:
    out = tmp_path / "score"
    cap = _manifest(tmp_path / "captured.txt", list(CAPTURED))
    code, stdout, err = _score(capsys, f"captured={cap}", f"generated={MOTIONS / GENERATED}", "--out", str(out), *FAST)
    assert code == 0, err
    lines = stdout.splitlines()
    assert lines[0] == "score on op3" and lines[1].split()[:3] == ["set", "samples", "executable"]
    assert lines[3].split()[:2] == ["captured", "1"] and lines[4].split()[:2] == ["generated", "3"]
    assert "4 samples; 0 already scored" in err and "4 to do" in err
    for name in ("score.csv", "score.json", "score.md", "score.html", "captured.jsonl", "generated.jsonl"):
        assert (out / name).stat().st_size > 0
    html = (out / "score.html").read_text()
    assert html.count("data:image/png;base64,") == 2 and "generated" in html
    md = (out / "score.md").read_text()
    assert "| set | samples | executable |" in md and "| generated | 3 |" in md
    figs = _figures(out)
    for name, f in figs.items():
        assert f["samples"] == f["executable"] + f["not_executable"] + f["errors"]
        assert f["fidelity_samples"] == f["samples"] - f["errors"]
        assert 0 <= f["contact_agreement"] <= 1 and f["keypoint_error_cm"] > 0 and f["keypoint_error_pose_cm"] > 0
        # batch-report on the set's results file says the same
        assert main(["batch-report", str(out / f"{name}.jsonl"), "--json", "-"]) == 0
        report = json.loads(capsys.readouterr().out)
        assert (report["clips"], report["feasible"], report["infeasible"], report["errors"]) == (
            f["samples"], f["executable"], f["not_executable"], f["errors"])
        assert report["executable_rate"] == pytest.approx(f["executable_share"], abs=1e-4)
        assert dict(list(report["failed_checks"].items())[:3]) == f["top_checks"]
        rows = [json.loads(x) for x in (out / f"{name}.jsonl").read_text().splitlines()]
        tempos = sorted(r["figures"]["tempo"] for r in rows if r["feasible"] and not r["error"])
        if tempos:
            assert f["tempo_median"] == pytest.approx(float(np.median(tempos)), abs=1e-3)
        assert f["fallback_share"] == pytest.approx(sum(bool(r["figures"].get("fallback")) for r in rows
                                                        if not r["error"]) / len(rows), abs=1e-4)
    csv_lines = (out / "score.csv").read_text().splitlines()
    assert csv_lines[0].startswith("name,samples,frames,executable") and len(csv_lines) == 3

    # a rerun scores nothing new and prints the same table, throughput included (it is read from the rows)
    code, again, err = _score(capsys, f"captured={cap}", f"generated={MOTIONS / GENERATED}", "--out", str(out), *FAST)
    assert code == 0 and again == stdout and "4 already scored" in err and "0 to do" in err

    # resume: one more sample in a set -> only that one is processed, the old rows stay as they were
    before = {k: (out / k).read_text() for k in ("captured.jsonl", "generated.jsonl")}
    _manifest(cap, [*CAPTURED, "humanml3d_joints/M010968.npy"])
    code, _, err = _score(capsys, f"captured={cap}", f"generated={MOTIONS / GENERATED}", "--out", str(out), *FAST)
    assert code == 0 and "4 already scored" in err and "1 to do" in err
    assert (out / "generated.jsonl").read_text() == before["generated.jsonl"]
    assert (out / "captured.jsonl").read_text().startswith(before["captured.jsonl"])
    assert _figures(out)["captured"]["samples"] == 2 and _figures(out)["generated"] == figs["generated"]

    # determinism: a fresh run of the same inputs gives the same figures (the throughput aside)
    fresh = tmp_path / "fresh"
    _manifest(cap, list(CAPTURED))
    code, _, _ = _score(capsys, f"captured={cap}", f"generated={MOTIONS / GENERATED}", "--out", str(fresh), *FAST)
    assert code == 0 and _without_timing(_figures(fresh)) == _without_timing(figs)


@requires_shared
def test_nan_sample_is_an_error_row_the_others_are_scored(tmp_path: Path, capsys) -> None:
    raw = np.load(MOTIONS / "humanml3d_joints/M010968.npy")[:40]
    batch = np.stack([raw, raw])
    batch[1, 7, 4] = np.nan
    np.save(tmp_path / "two.npy", batch)
    code, stdout, err = _score(capsys, str(tmp_path / "two.npy"), "--out", str(tmp_path / "o"), *FAST)
    assert code == 0, err
    f = _figures(tmp_path / "o")["two"]
    assert (f["samples"], f["errors"], f["executable"] + f["not_executable"]) == (2, 1, 1)
    rows = [json.loads(x) for x in (tmp_path / "o" / "two.jsonl").read_text().splitlines()]
    bad = next(r for r in rows if r["clip"] == 1)
    good = next(r for r in rows if r["clip"] == 0)
    assert "NaN" in bad["error"] and good["error"] is None and good["fidelity"]["keypoint_error_m"] > 0


@requires_shared
def test_padded_batch_file_without_lengths_is_an_error_row_with_them_every_sample_is_scored(tmp_path: Path, capsys) -> None:
    raw = np.load(MOTIONS / "humanml3d_joints/M010968.npy")[:40]
    batch = np.stack([raw, raw])
    batch[1, 30:] = 0.0  # a generator's padding after a 30-frame sample
    np.save(tmp_path / "padded.npy", batch)
    code, _, err = _score(capsys, str(tmp_path / "padded.npy"), "--out", str(tmp_path / "o"), *FAST)
    assert code == 0, err
    rows = {r["clip"]: r for r in map(json.loads, (tmp_path / "o" / "padded.jsonl").read_text().splitlines())}
    assert rows[0]["error"] is None and rows[0]["frames"] == 40
    assert "10 all-zero frames (frames 30-39 of 40)" in rows[1]["error"] and "lengths" in rows[1]["error"]
    np.savez(tmp_path / "padded.npz", joints=batch, lengths=np.array([40, 30]), fps=20.0)
    code, _, err = _score(capsys, str(tmp_path / "padded.npz"), "--out", str(tmp_path / "o"), *FAST)
    assert code == 0, err
    rows = {r["clip"]: r for r in map(json.loads, (tmp_path / "o" / "padded.jsonl").read_text().splitlines())}
    assert [rows[i]["error"] for i in (0, 1)] == [None, None] and [rows[i]["frames"] for i in (0, 1)] == [40, 30]


def test_unknown_robot_one_line_exit_2(tmp_path: Path) -> None:
    clip = tmp_path / "c.npy"
    np.save(clip, np.zeros((5, 22, 3)))
    r = subprocess.run([sys.executable, "-m", "motion2robot", "score", str(clip), "--robot", "nosuchbot",
                        "--out", str(tmp_path / "o"), "-q"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, r.stderr
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("motion2robot: error: ") and "nosuchbot" in r.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("args, words", [(["--out", "FILE"], "must be a folder"),
                                         (["--jobs", "0"], "--jobs/-j: must be a whole number of workers in [1, 4096]")])
def test_bad_options_exit_2(tmp_path: Path, capsys, args: list[str], words: str) -> None:
    clip = tmp_path / "c.npy"
    np.save(clip, np.zeros((5, 22, 3)))
    (tmp_path / "FILE").write_text("x")
    args = [a.replace("FILE", str(tmp_path / "FILE")) for a in args]
    if "--out" not in args:
        args += ["--out", str(tmp_path / "o")]
    try:
        code = main(["score", str(clip), *args, "-q"])
    except SystemExit as e:  # a value refused while the options are parsed
        code = e.code
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("motion2robot: error: ") and words in err


def test_duplicate_set_names_and_missing_input(tmp_path: Path, capsys) -> None:
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    assert main(["score", f"x={tmp_path / 'a'}", f"x={tmp_path / 'b'}", "--out", str(tmp_path / "o")]) == 2
    assert "two INPUTS make the set 'x'" in capsys.readouterr().err
    assert main(["score", str(tmp_path / "nope"), "--out", str(tmp_path / "o")]) == 2
    assert "no such file or folder" in capsys.readouterr().err


@requires_shared
def test_killed_run_loses_nothing(tmp_path: Path) -> None:
    """SIGKILL the run after its first row: the rows written stay, the rerun does only the rest."""
    out = tmp_path / "o"
    cmd = [sys.executable, "-m", "motion2robot", "score", f"gen={MOTIONS / GENERATED}", "--out", str(out),
           "-q", "--no-physics", "-j", "1"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    results = out / "gen.jsonl"
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and proc.poll() is None:
        if results.exists() and results.read_text().count("\n") >= 1:
            break
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    kept = results.read_text().splitlines()
    assert 1 <= len(kept) <= 3
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert f"{len(kept)} already scored" in r.stderr and f"{3 - len(kept)} to do" in r.stderr
    rows = results.read_text().splitlines()
    assert rows[:len(kept)] == kept and len(rows) == 3
    assert sorted(json.loads(x)["clip"] for x in rows) == [0, 1, 2]


@requires_shared
def test_trajectory_error_where_a_path_was_requested(tmp_path: Path, capsys) -> None:
    """A clip with a requested root path (--trajectory: here its own pelvis path on the ground,
    x and z of the y-up file) gets the trajectory error column; clips without one show '-'."""
    raw = np.load(MOTIONS / "humanml3d_joints/M010968.npy")[:40]
    np.save(tmp_path / "clip.npy", raw)
    np.savetxt(tmp_path / "path.csv", raw[:, 0, [0, 2]], delimiter=",")
    code, stdout, err = _score(capsys, f"ctl={tmp_path / 'clip.npy'}", "--trajectory", str(tmp_path / "path.csv"),
                               "--out", str(tmp_path / "o"), *FAST)
    assert code == 0, err
    f = _figures(tmp_path / "o")["ctl"]
    assert f["trajectory_samples"] == 1 and 0 <= f["trajectory_error_m"] < 0.05
    assert f"{100 * f['trajectory_error_m']:.1f} cm (1)" in stdout.splitlines()[3]

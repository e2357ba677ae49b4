"""Batch summaries, CSV/HTML export and the ``batch-report`` command."""

from __future__ import annotations

import csv
import json

from motion2robot.batch.results import ResultWriter
from motion2robot.batch.summary import format_summary, pattern, summarize, write_csv
from motion2robot.cli import main


def _row(key, feasible=None, failed=(), reasons=(), error=None, total=0.1, frames=100, **figures):
    return {"key": key, "path": key.split("#")[0], "clip": 0, "frames": frames, "feasible": feasible,
            "failed_checks": list(failed), "reasons": list(reasons), "figures": figures, "error": error,
            "prompt": "a <b>person</b> waves", "robot": "op3",
            "timings": {"read_s": 0.01, "retarget_s": total / 2, "check_s": total / 4, "total_s": total}}


ROWS = [
    _row("/d/a.npy#0", True, total=0.2, max_torque_ratio=0.4),
    _row("/d/b.npy#0", False, ["joint_limits", "balance"],
         ["r_knee exceeds its upper limit by 0.31 rad in frames 12-40",
          "ZMP leaves the support polygon in 5 frames",
          "... and 2 more joints over their limits"],
         total=1.5),
    _row("/d/c.npy#0", False, ["joint_limits"], ["r_knee exceeds its upper limit by 0.05 rad in frames 3-4"],
         total=0.7),
    _row("/d/e.npy#0", error="read: /d/e.npy: is empty (0 bytes); re-export the file", total=0.001, frames=None),
    _row("/d/f.npy#0", error="read: /d/f.npy: is empty (0 bytes); re-export the file", total=0.002, frames=None),
]


def test_pattern_groups_numbers_frames_and_the_clips_path():
    assert pattern("/d/e.npy: 3 frames of 1.5e-3 m", "/d/e.npy") == "<file>: # frames of # m"
    assert pattern("right hip pitch needs 30.83 N*m, 7.5x its servo's 4.1 N*m, in frames 18, 22-24, ... "
                   "(5 runs) (from 0.60 s)") == "right hip pitch needs # N*m, #x its servo's # N*m"
    assert pattern("the ZMP leaves the support polygon at 0.00 s (frames 0-2, ... (5 runs)), by up to 1.7 m") \
        == "the ZMP leaves the support polygon at # s, by up to # m"


def test_summary_counts_rates_checks_reasons_slowest():
    s = summarize(ROWS)
    assert (s.clips, s.feasible, s.infeasible, s.errors, s.frames) == (5, 1, 2, 2, 300)
    assert s.executable_rate == 0.2 and s.solved_rate == 1 / 3
    assert s.failed_checks == (("joint_limits", 2), ("balance", 1))
    assert s.reasons[0][1] == 2 and "r_knee exceeds" in s.reasons[0][2]
    assert len(s.reasons) == 2  # the "... and 2 more" continuation is not a reason
    assert s.error_kinds == (("read: <file>: is empty; re-export the file", 2,
                              "read: /d/e.npy: is empty (0 bytes); re-export the file"),)
    assert [k for k, _, _ in s.slowest[:2]] == ["/d/b.npy#0", "/d/c.npy#0"]
    text = format_summary(s, robot="op3")
    assert "executable: 1 (20.0%)" in text and "joint_limits" in text and "slowest clips" in text
    assert summarize([]).executable_rate is None


def test_csv_has_one_line_per_clip_with_figures(tmp_path):
    path = write_csv(ROWS, tmp_path / "o.csv")
    with open(path, newline="") as fh:
        lines = list(csv.DictReader(fh))
    assert len(lines) == 5
    assert lines[1]["failed_checks"] == "joint_limits;balance" and lines[0]["fig_max_torque_ratio"] == "0.4"
    assert lines[3]["error"].startswith("read:")


def test_batch_report_command(tmp_path, capsys):
    res = tmp_path / "r.jsonl"
    with ResultWriter(res) as w:
        w.write_all(ROWS)
    with open(res, "a") as fh:
        fh.write('{"key": "/d/torn')  # a batch killed mid-write
    html, csv_path, js = tmp_path / "r.html", tmp_path / "r.csv", tmp_path / "s.json"
    assert main(["batch-report", str(res), "--html", str(html), "--csv", str(csv_path), "--json", str(js)]) == 0
    out, err = capsys.readouterr()
    assert "5 clips" in out and "executable: 1 (20.0%)" in out and "ignored 1 unreadable line" in err
    page = html.read_text()
    assert page.startswith("<!DOCTYPE html>") and "<script" not in page
    assert "a &lt;b&gt;person&lt;/b&gt; waves" in page and page.count('<tr class="error">') == 2
    assert json.loads(js.read_text())["failed_checks"] == {"joint_limits": 2, "balance": 1}
    assert csv_path.read_text().count("\n") == 6


def test_batch_report_on_missing_or_empty_file_exits_2(tmp_path, capsys):
    assert main(["batch-report", str(tmp_path / "none.jsonl")]) == 2
    (tmp_path / "empty.jsonl").write_text("")
    assert main(["batch-report", str(tmp_path / "empty.jsonl")]) == 2
    assert "holds no result rows" in capsys.readouterr().err

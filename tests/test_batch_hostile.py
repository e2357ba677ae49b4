"""Batch survives any file name and any concurrency (issue 20): a file name that is not UTF-8
made every run fail with exit 3; '--redo' rewrote the results before taking the lock (a
concurrent batch lost 50 rows); FIFOs, devices, broken links and directories named like motions
were skipped without a row; each gets an error row now."""

from __future__ import annotations

import json
import os

import numpy as np

from motion2robot.batch.results import batch_lock, dumps_row, read_rows
from motion2robot.cli import main
from tests.test_motion_support import walking_yup


def _folder(tmp_path):
    d = tmp_path / "d"
    d.mkdir()
    with open(os.fsencode(d) + b"/caf\xe9.npy", "wb") as fh:  # Latin-1 name: not UTF-8
        np.save(fh, walking_yup(30))
    np.save(d / "ok.npy", walking_yup(30))
    os.mkfifo(d / "fifo.npy")
    (d / "dir.npy").mkdir()
    os.symlink(tmp_path / "gone.npy", d / "broken.npy")
    os.symlink("/dev/null", d / "device.npy")  # a device named like a motion
    return d


def test_non_utf8_names_and_special_files_each_get_a_row_and_resume_works(tmp_path, capsys):
    d = _folder(tmp_path)
    out = tmp_path / "r.jsonl"
    argv = ["batch", str(d), "--robot", "op3", "--out", str(out), "--no-physics", "-q"]
    assert main(argv) == 0, capsys.readouterr().err
    rows = read_rows(out).rows
    assert len(rows) == 6
    out.read_bytes().decode("utf-8")  # the file stays valid UTF-8
    errors = {os.path.basename(r["key"].split("#")[0]): r["error"] for r in rows}
    assert "FIFO" in errors["fifo.npy"] and "is a directory" in errors["dir.npy"]
    assert "broken symbolic link" in errors["broken.npy"]  # the row names the link, not its missing target
    assert "device.npy: is a character device" in errors["null"]  # keyed by the device, naming the link
    assert any(k.encode("utf-8", "surrogateescape") == b"caf\xe9.npy" for k in errors)
    capsys.readouterr()
    assert main(argv) == 0  # the second run resumes: nothing to do, nothing duplicated
    assert "6 already in" in capsys.readouterr().err and len(out.read_text().splitlines()) == 6


def test_a_row_with_a_surrogate_name_round_trips():
    row = {"key": "/x/caf\udce9.npy#0", "prompt": "ein Mädchen"}
    line = dumps_row(row)
    line.encode("utf-8")
    assert json.loads(line) == row


def test_redo_takes_the_lock_before_touching_the_file(tmp_path, capsys):
    np.save(tmp_path / "a.npy", walking_yup(30))
    out = tmp_path / "r.jsonl"
    before = "".join(json.dumps({"key": f"/elsewhere/{i}.npy#0", "error": None}) + "\n" for i in range(50))
    out.write_text(before)
    with batch_lock(out):  # another batch is running on this file
        code = main(["batch", str(tmp_path / "a.npy"), "--robot", "op3", "--out", str(out), "--redo", "-q"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and err[-1].startswith("motion2robot: error: ") and "another batch" in err[-1]
    assert out.read_text() == before  # nothing rewritten, nothing lost

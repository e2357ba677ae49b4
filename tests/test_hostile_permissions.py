"""Files the user may not read or write are one-line errors with exit 2 (issue 20: 'an unreadable
file' was an internal error, exit 3), and a batch gives an unreadable file an error row.

Root reads any file whatever its mode, so as root the commands run in a child process without
the capabilities that let root ignore file permissions (``setpriv``); the child first checks
that the file really is unreadable to it, so the test cannot pass by reading the file."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests._shared import MOTIONS
from tests.test_motion_support import bvh_text, walking_yup

ROOT = Path(__file__).resolve().parents[1]

_CHILD = """
import contextlib, io, json, sys
from motion2robot.cli import main
unreadable, runs = json.loads(sys.argv[1])
for p in unreadable:
    try:
        open(p, "rb").close()
        sys.exit("test set-up: %s is readable to this process" % p)
    except PermissionError:
        pass
out = []
for argv in runs:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(argv)
    out.append([code, err.getvalue()])
print(json.dumps(out))
"""


def _unprivileged_prefix() -> list[str]:
    if os.geteuid() != 0:
        return []
    setpriv = shutil.which("setpriv")
    cmd = [setpriv, "--bounding-set", "-dac_override,-dac_read_search"] if setpriv else None
    if cmd is None or subprocess.run([*cmd, "true"], capture_output=True).returncode != 0:
        pytest.skip("root reads every file, and setpriv cannot drop that capability here")
    return cmd


def _run(unreadable: list[Path], runs: list[list[str]]) -> list[tuple[int, list[str]]]:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run([*_unprivileged_prefix(), sys.executable, "-c", _CHILD,
                           json.dumps([[str(p) for p in unreadable], runs])],
                          capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return [(code, [ln for ln in err.splitlines() if ln.strip()]) for code, err in json.loads(proc.stdout)]


def _one_line_error(code: int, err: list[str], path: Path, *words: str) -> None:
    assert code == 2 and len(err) == 1 and err[0].startswith("motion2robot: error: "), (code, err)
    assert str(path) in err[0] and "internal error" not in err[0], err
    for w in words:
        assert w in err[0], err


def test_unreadable_inputs_are_one_line_errors(tmp_path):
    from tests.fuzz.corpus import robot_npz

    npy = tmp_path / "m.npy"
    np.save(npy, walking_yup(30))
    bvh = tmp_path / "m.bvh"
    bvh.write_text(bvh_text())
    motion = robot_npz(tmp_path, "r.npz")
    toml = tmp_path / "bot.toml"
    toml.write_text((ROOT / "robots" / "op3" / "op3.toml").read_text())
    folder = tmp_path / "clips"
    folder.mkdir()
    np.save(folder / "a.npy", walking_yup(30))
    np.save(folder / "b.npy", walking_yup(30))
    locked = [npy, bvh, motion, toml, folder / "b.npy"]
    for p in locked:
        p.chmod(0)
    results = _run(locked, [["inspect", str(npy)], ["inspect", str(bvh)], ["check", str(motion), "--no-physics"],
                            ["stream", str(motion), "--dry-run", "--telemetry", str(tmp_path / "t.jsonl")],
                            ["robots", "show", str(toml)], ["inspect", str(folder)]])
    for (code, err), path in zip(results[:4], [npy, bvh, motion, motion]):
        _one_line_error(code, err, path, "cannot be read (Permission denied)", "permissions")
    _one_line_error(*results[4], toml, "permission denied")  # met deep in the config loader
    _one_line_error(*results[5], folder / "b.npy", "cannot be read (Permission denied)")


def test_a_batch_gives_an_unreadable_file_an_error_row(tmp_path):
    folder = tmp_path / "clips"
    folder.mkdir()
    np.save(folder / "a.npy", walking_yup(30))
    np.save(folder / "b.npy", walking_yup(30))
    (folder / "b.npy").chmod(0)
    out = tmp_path / "r.jsonl"
    [(code, err)] = _run([folder / "b.npy"], [["batch", str(folder), "--robot", "op3", "--out", str(out),
                                               "--no-physics", "-q"]])
    assert code == 0, err
    rows = {Path(json.loads(ln)["path"]).name: json.loads(ln) for ln in out.read_text().splitlines()}
    assert set(rows) == {"a.npy", "b.npy"}
    assert "cannot be read (Permission denied)" in rows["b.npy"]["error"]


@pytest.mark.skipif(MOTIONS is None, reason="../shared (real motion clips) is absent")
def test_an_output_folder_without_write_permission_names_the_output(tmp_path):
    locked = tmp_path / "ro"
    locked.mkdir()
    probe = locked / "probe"
    probe.write_text("x")
    probe.chmod(0)
    locked.chmod(0o555)
    out = locked / "o.npz"
    [(code, err)] = _run([probe], [["retarget", str(MOTIONS / "humanml3d_joints" / "M010968.npy"), "-o", str(out)]])
    _one_line_error(code, err, out, "cannot be written (permission denied)")
    assert not list(locked.glob("*.part*"))

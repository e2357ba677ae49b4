"""``motion2robot check``: exit codes, table, JSON report, human motion retargeted first."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.robot import load_robot
from motion2robot.validate import examples
from tests._shared import MOTIONS, requires_shared


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def test_feasible_motion_exits_0_and_writes_json(op3, tmp_path, capsys):
    path = examples.waving(op3, seconds=1.0).save(tmp_path / "wave.npz")
    code = main(["check", str(path), "--json", str(tmp_path / "r.json"), "--no-physics"])
    out = capsys.readouterr().out
    assert code == 0
    assert out.splitlines()[0].startswith("op3: 50 frames at 50 fps")
    assert "FEASIBLE" in out and "report written to" in out
    data = json.loads((tmp_path / "r.json").read_text())
    assert data["feasible"] is True and data["checks"]["rollout"]["skipped"]


def test_infeasible_motion_exits_1_with_reasons(op3, tmp_path, capsys):
    path = examples.slow_lean(op3).save(tmp_path / "lean.npz")
    code = main(["check", str(path)])
    out = capsys.readouterr().out
    assert code == 1
    assert "INFEASIBLE (balance, rollout)" in out
    assert "falls at" in out


def test_errors_exit_2(tmp_path, capsys):
    assert main(["check", str(tmp_path / "missing.npz")]) == 2
    assert "missing.npz" in capsys.readouterr().err
    path = examples.standing(load_robot("op3"), seconds=0.2).save(tmp_path / "s.npz")
    assert main(["check", str(path), "--robot", "no_such_robot"]) == 2


@requires_shared
def test_human_motion_is_retargeted_then_checked(tmp_path, capsys):
    pytest.importorskip("motion2robot.retarget")
    clip = MOTIONS / "humanml3d_joints" / "M010968.npy"
    code = main(["check", str(clip), "--no-physics", "--json", str(tmp_path / "r.json")])
    out = capsys.readouterr().out
    assert code in (0, 1), out
    data = json.loads((tmp_path / "r.json").read_text())
    assert data["robot"] == "op3" and data["frames"] == 70
    # the retargeter names the human root path, so the trajectory figure is computed
    assert "mean_error_m" in data["checks"]["trajectory"]
    assert np.isfinite(data["checks"]["trajectory"]["mean_error_m"])
    verdict_line = out.splitlines()[-2]  # the last line says where the report went
    assert verdict_line == "FEASIBLE" if code == 0 else verdict_line.startswith("INFEASIBLE (")


@requires_shared
def test_multi_clip_file_needs_a_clip(capsys):
    code = main(["check", str(MOTIONS / "mdm_results" / "mdm_walk_pickup_results.npy"), "--no-physics"])
    assert code == 2
    assert "--clip" in capsys.readouterr().err

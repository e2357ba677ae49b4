"""FeasibilityReport, verdict, reasons wording and the verdict table."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motion2robot.errors import InputFileError, UserError
from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate import CheckOptions, check, examples, verdict_table
from motion2robot.validate.reasons import human_name, reasons
from motion2robot.validate.report import verdict


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


@pytest.mark.parametrize("name, human", [
    ("r_knee", "right knee"), ("l_sho_pitch", "left shoulder pitch"), ("l_el_link", "left elbow"),
    ("left_knee_joint", "left knee"), ("head_pan", "head pan"), ("waist_yaw_joint", "waist yaw"),
])
def test_human_names(name, human):
    assert human_name(name) == human


def test_verdict_ignores_trajectory_and_skipped_checks():
    checks = {"joint_limits": {"ok": True}, "rollout": {"ok": True, "skipped": "--no-physics"},
              "trajectory": {"ok": False}}
    assert verdict(checks)
    assert not verdict({**checks, "balance": {"ok": False}})


def test_reasons_combine_balance_with_the_fall():
    checks = {
        "balance": {"ok": False, "com_worst": {"by_m": 0.014, "frame": 47, "time_s": 2.35},
                    "com_outside_frames": [45, 46, 47], "zmp_worst": None, "flight_frames": []},
        "rollout": {"ok": False, "fell": True, "fall_time_s": 2.6, "fall_cause": "tilt"},
    }
    out = reasons(checks, fps=20.0)
    assert out == [("CoM leaves the support polygon at 2.25 s (frames 45-47), by up to 14 mm at 2.35 s; "
                   "the robot falls at 2.60 s in playback (its torso tips over)")]


def test_no_physics_skips_the_rollout(op3):
    rep = check(examples.standing(op3, seconds=0.5), op3, CheckOptions(physics=False))
    assert rep.feasible and rep.checks["rollout"]["skipped"] == "--no-physics"
    assert "rollout_q" not in rep.series
    table = verdict_table(rep)
    assert "rollout" in table and "skipped" in table and table.splitlines()[-1] == "FEASIBLE"


def test_table_lists_failures_and_reasons(op3):
    rep = check(examples.knee_past_limit(op3), op3, CheckOptions(physics=False))
    table = verdict_table(rep)
    row = next(line for line in table.splitlines() if line.startswith("joint_limits"))
    assert "FAIL" in row and "10-20" in row
    assert "- left knee beyond its upper limit" in table
    assert table.splitlines()[-1].startswith("INFEASIBLE (joint_limits")
    d = json.loads(json.dumps(rep.to_dict()))
    assert d["checks"]["joint_limits"]["frames"] == list(range(10, 21))
    assert d["figures"]["failed"][0] == "joint_limits"


def test_nan_frames_are_refused(op3):
    q = examples.standing(op3, seconds=0.2).qpos.copy()
    q[3, 9] = np.nan
    with pytest.raises(InputFileError, match="frames 3"):
        check(RobotMotion(q, 50, op3.joint_names, "op3"), op3)


def test_a_motion_for_another_robot_is_refused(op3):
    q = np.zeros((5, 7 + 3))
    q[:, 3] = 1
    with pytest.raises(InputFileError, match="--robot"):
        check(RobotMotion(q, 20, ("a", "b", "c"), "other"), op3)


@pytest.mark.parametrize("bad", [{"timestep": 0.005}, {"torque_margin": 0.0}, {"collision_depth": -1.0}, {"min_run": 0}])
def test_options_are_validated(bad):
    with pytest.raises(UserError):
        CheckOptions(**bad)

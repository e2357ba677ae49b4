"""Acceptance cases of the feasibility check on the bundled OP3 (constructed motions)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motion2robot.robot import load_robot
from motion2robot.validate import CHECK_NAMES, check, examples, verdict_table


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


@pytest.fixture(scope="module")
def reports(op3):
    return {name: check(getattr(examples, name)(op3), op3)
            for name in ("standing", "waving", "knee_past_limit", "arm_through_torso", "slow_lean")}


@pytest.mark.parametrize("name", ["standing", "waving"])
def test_standing_and_waving_pass_every_check(reports, name):
    rep = reports[name]
    failed = {n: c for n, c in rep.checks.items() if not c["ok"]}
    assert rep.feasible, failed
    assert set(rep.checks) == set(CHECK_NAMES)
    assert rep.checks["rollout"]["fell"] is False
    assert rep.checks["balance"]["min_com_margin_m"] > 0.02
    assert rep.reasons == []
    assert verdict_table(rep).endswith("FEASIBLE")


def test_waving_moves_the_elbow_without_exceeding_limits(reports):
    c = reports["waving"].checks
    assert 0.2 < c["velocity_limits"]["max_ratio"] < 1.0
    assert 0.0 < c["torque_limits"]["max_ratio"] < 1.0


def test_knee_past_its_limit_fails_joint_limits_in_those_frames(reports):
    rep = reports["knee_past_limit"]
    jl = rep.checks["joint_limits"]
    assert not rep.feasible and not jl["ok"]
    assert jl["frames"] == list(range(10, 21))
    (v,) = jl["violations"]
    assert v["joint"] == "l_knee" and v["by_rad"] == pytest.approx(0.2, abs=1e-6)
    assert any(r.startswith("left knee beyond its upper limit by 0.20 rad in frames 10-20") for r in rep.reasons)


def test_arm_through_the_torso_fails_self_collision(reports):
    sc = reports["arm_through_torso"].checks["self_collision"]
    assert not sc["ok"] and sc["max_depth_m"] > 0.01
    pairs = {(v["body1"], v["body2"]) for v in sc["violations"]}
    assert ("body_link", "l_el_link") in pairs
    # the collision happens around the middle of the swing, not at the start or end
    assert 0 not in sc["frames"] and 50 in sc["frames"]
    assert any("left elbow" in r and "collide" in r for r in reports["arm_through_torso"].reasons)


def test_slow_lean_fails_balance_and_falls_in_playback(reports):
    rep = reports["slow_lean"]
    bal, roll = rep.checks["balance"], rep.checks["rollout"]
    assert not bal["ok"] and bal["min_com_margin_m"] < 0
    assert bal["com_first_out_s"] is not None
    assert not roll["ok"] and roll["fell"]
    # the robot falls once the CoM is near the heel edge, not at the start
    assert 1.0 < roll["fall_time_s"] <= 3.0
    assert rep.checks["joint_limits"]["ok"] and rep.checks["torque_limits"]["ok"]
    assert any("falls at" in r for r in rep.reasons)


def test_report_is_json_serialisable_and_has_series(reports, tmp_path):
    rep = reports["slow_lean"]
    path = rep.to_json(tmp_path / "r.json")
    data = json.loads(path.read_text())
    assert data["feasible"] is False and data["robot"] == "op3" and data["frames"] == 150
    assert set(data["checks"]) == set(CHECK_NAMES)
    assert "series" not in data
    T, n = 150, 20
    s = rep.series
    assert s["q"].shape == (T, n) and s["qvel"].shape == (T, n) and s["torque_ratio"].shape == (T, n)
    assert s["com_xy"].shape == (T, 2) and s["zmp_xy"].shape == (T, 2) and s["support_margin"].shape == (T,)
    assert s["foot_height"].shape == (T, 2) and s["contacts"].shape == (T, 2)
    assert s["rollout_q"].shape == (T, n) and s["rollout_time"].shape == (T,)
    assert np.nanmin(s["support_margin"]) < 0 < s["support_margin"][0]

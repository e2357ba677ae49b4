"""ground on real clips: a planted sole that twists in place, a swing foot that skims, a clean stand."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate import CheckOptions, check
from motion2robot.validate.context import prepare
from motion2robot.validate.ground import ground
from tests._real_clips import standing_wave, yaw_about
from tests._shared import requires_shared

pytestmark = requires_shared


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


@pytest.fixture(scope="module")
def stand(op3):
    return standing_wave(op3)


def _ground(motion, robot, **opts):
    return ground(prepare(motion, robot, CheckOptions(physics=False, **opts)))


def test_a_clean_standing_clip_passes_ground(op3, stand):
    out = _ground(stand, op3)
    assert out["ok"], out
    assert out["slipping"] == [] and out["skimming"] == [] and out["max_slip_m_s"] < 1e-6
    report = check(stand, op3, CheckOptions(physics=False))
    assert "ground" not in report.figures["failed"]
    assert not [r for r in report.reasons if "sole" in r or "skims" in r]


def test_a_sole_twisting_about_its_pinned_centre_fails_at_its_corners(op3, stand):
    """The whole robot turns at 0.3 rad/s about the left sole's centre: that centre does not move,
    its corners move ~2 cm/s (far below the old 0.15 m/s skating line): the sole twists."""
    ctx = prepare(stand, op3, CheckOptions(physics=False))
    centre = ctx.kin.corners[0, 0, :, :2].mean(axis=0)
    turned = yaw_about(stand, centre, 0.3)
    tctx = prepare(turned, op3, CheckOptions(physics=False))
    centre_speed = np.linalg.norm(np.diff(tctx.kin.corners[:, 0, :, :2].mean(axis=1), axis=0), axis=1) * stand.fps
    assert centre_speed.max() < 1e-3
    out = ground(tctx)
    assert not out["ok"]
    left = [v for v in out["slipping"] if v["foot"] == "left"]
    assert [v["kind"] for v in left] == ["twist"]
    assert left[0]["point"].endswith("corner")
    half_diagonal = np.linalg.norm(ctx.kin.corners[0, 0, :, :2] - centre, axis=1).max()
    assert left[0]["speed_m_s"] == pytest.approx(0.3 * half_diagonal, rel=0.05)
    assert 0.01 < left[0]["speed_m_s"] < 0.15
    assert left[0]["frames"][0] == 0 and left[0]["frames"][-1] == stand.num_frames - 1
    report = check(turned, op3, CheckOptions(physics=False))
    sentence = next(r for r in report.reasons if r.startswith("left sole twists"))
    assert f"at its {left[0]['point']}" in sentence and "while planted" in sentence and "cm/s" in sentence


@pytest.mark.parametrize(("lift", "skims"), [(0.003, True), (0.03, False)])
def test_a_foot_moving_just_above_the_floor_skims(op3, stand, lift, skims):
    """The real standing pose carried forward at 0.1 m/s 3 mm above the floor (inside the OP3's
    5 mm swing clearance) skims; 3 cm above the floor it is clear."""
    q = stand.qpos.copy()
    q[:, 2] += lift
    q[:, 0] += 0.1 * np.arange(len(q)) / stand.fps
    moved = RobotMotion(q, stand.fps, stand.joint_names, stand.robot)
    out = _ground(moved, op3)
    assert out["slipping"] == [] and out["ok"] is not skims
    if skims:
        assert {v["foot"] for v in out["skimming"]} == {"left", "right"}
        v = out["skimming"][0]
        assert v["height_m"] == pytest.approx(lift, abs=1e-3) and v["speed_m_s"] == pytest.approx(0.1, rel=0.05)
        text = " ".join(check(moved, op3, CheckOptions(physics=False)).reasons)
        assert "foot skims the floor at 3 mm" in text and "5 mm of clearance" in text


def test_the_thresholds_reach_check_through_the_cli(op3, stand, tmp_path, capsys):
    """--slip-speed and --swing-clearance set the lines ``ground`` draws."""
    from motion2robot.cli import main

    q = stand.qpos.copy()
    q[:, 0] += 0.02 * np.arange(len(q)) / stand.fps  # a slow 2 cm/s slide
    path = RobotMotion(q, stand.fps, stand.joint_names, "op3").save(tmp_path / "slide.npz")
    strict, loose = tmp_path / "strict.json", tmp_path / "loose.json"
    main(["check", str(path), "--no-physics", "--json", str(strict)])
    main(["check", str(path), "--no-physics", "--json", str(loose), "--slip-speed", "0.05", "--swing-clearance", "0.004"])
    capsys.readouterr()
    g_strict = json.loads(strict.read_text())["checks"]["ground"]
    g_loose = json.loads(loose.read_text())["checks"]["ground"]
    assert not g_strict["ok"] and g_strict["slip_speed_m_s"] == 0.01
    assert g_loose["ok"] and g_loose["slip_speed_m_s"] == 0.05 and g_loose["swing_clearance_m"] == 0.004

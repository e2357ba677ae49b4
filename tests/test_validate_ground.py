"""ground: penetration below the floor and feet skating; balance: support, flight, margins."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate import examples
from motion2robot.validate.balance import balance
from motion2robot.validate.context import prepare
from motion2robot.validate.ground import ground
from motion2robot.validate.options import CheckOptions


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def ctx_of(robot, q, fps=50.0, meta=None, **opts):
    return prepare(RobotMotion(q, fps, robot.joint_names, robot.name, meta=meta or {}), robot, CheckOptions(**opts))


def test_standing_touches_the_floor_without_penetration_or_skating(op3):
    out = ground(ctx_of(op3, examples.standing(op3).qpos))
    assert out["ok"] and out["max_penetration_m"] < 1e-3
    assert out["penetrations"] == [] and out["slipping"] == [] and out["skimming"] == []
    assert out["non_foot_contacts"] == [] and out["max_slip_m_s"] < 1e-6


def test_sinking_into_the_floor_fails_with_the_depth(op3):
    q = examples.standing(op3).qpos.copy()
    q[20:30, 2] -= 0.02
    out = ground(ctx_of(op3, q))
    assert not out["ok"] and out["frames"] == list(range(20, 30))
    names = {v["body"] for v in out["penetrations"]}
    assert names == {"left foot", "right foot"}
    assert out["max_penetration_m"] == pytest.approx(0.02, abs=2e-3)


def test_feet_sliding_on_the_floor_slip(op3):
    q = examples.standing(op3).qpos.copy()
    q[:, 0] += 0.4 * np.arange(len(q)) / 50.0  # the whole robot glides at 0.4 m/s
    out = ground(ctx_of(op3, q))
    assert not out["ok"] and {(v["foot"], v["kind"]) for v in out["slipping"]} == {("left", "slide"), ("right", "slide")}
    assert out["slipping"][0]["speed_m_s"] == pytest.approx(0.4, rel=0.02)
    assert out["max_penetration_m"] < 1e-3 and out["skimming"] == []


def test_a_slow_slide_fails_and_the_threshold_is_an_option(op3):
    """2 cm/s is far below the old 0.15 m/s skating line, but a planted sole must not move at all
    (> 1 cm/s fails); the line is ``slip_speed``."""
    q = examples.standing(op3).qpos.copy()
    q[:, 0] += 0.02 * np.arange(len(q)) / 50.0
    assert not ground(ctx_of(op3, q))["ok"]
    assert ground(ctx_of(op3, q, slip_speed=0.03))["ok"]


def test_contact_labels_do_not_excuse_a_sliding_sole(op3):
    """The floor does not read the motion's labels: soles on the floor that move slip even while
    labelled in the air."""
    q = examples.standing(op3).qpos.copy()
    q[:, 0] += 0.4 * np.arange(len(q)) / 50.0
    swing = np.zeros((len(q), 2), dtype=bool)
    out = ground(ctx_of(op3, q, meta={"contacts": swing.tolist()}))
    assert not out["ok"] and {v["foot"] for v in out["slipping"]} == {"left", "right"}


@pytest.mark.parametrize(("lift", "fails"), [(0.003, True), (0.02, False)])
def test_feet_gliding_just_above_the_floor_skim(op3, lift, fails):
    """3 mm above the floor is within the OP3's 5 mm clearance: a moving foot there skims; 2 cm
    above, it is clear of the floor."""
    q = examples.standing(op3).qpos.copy()
    q[:, 2] += lift
    q[:, 0] += 0.1 * np.arange(len(q)) / 50.0
    out = ground(ctx_of(op3, q))
    assert out["swing_clearance_m"] == pytest.approx(0.0052, abs=5e-4)
    assert out["slipping"] == [] and out["ok"] is not fails
    if fails:
        assert {v["foot"] for v in out["skimming"]} == {"left", "right"}
        assert out["skimming"][0]["height_m"] == pytest.approx(lift, abs=5e-4)
        assert out["skimming"][0]["speed_m_s"] == pytest.approx(0.1, rel=0.02)
    assert ground(ctx_of(op3, q, swing_clearance=lift / 2))["ok"]


def test_balance_flags_flight_and_reports_margins(op3):
    q = examples.standing(op3).qpos.copy()
    q[10:15, 2] += 0.03
    out = balance(ctx_of(op3, q))
    assert not out["ok"] and out["flight_frames"] == list(range(10, 15))
    assert balance(ctx_of(op3, q, allow_flight=True))["flight_frames"] == list(range(10, 15))
    stand = balance(ctx_of(op3, examples.standing(op3).qpos))
    assert stand["ok"] and stand["flight_frames"] == [] and stand["min_zmp_margin_m"] > 0.02


def test_balance_uses_the_contact_labels_of_the_meta(op3):
    """A foot moving fast but labelled in contact still supports the robot."""
    q = examples.standing(op3).qpos.copy()
    q[:, 0] += 0.4 * np.arange(len(q)) / 50.0
    unlabelled = ctx_of(op3, q)
    assert not unlabelled.support.any()
    labelled = ctx_of(op3, q, meta={"contacts": np.ones((len(q), 2), bool).tolist()})
    assert labelled.support.all()


def test_single_support_shrinks_the_polygon_to_one_foot(op3):
    ctx = ctx_of(op3, examples.standing(op3).qpos)
    both = balance(ctx)["min_com_margin_m"]
    # only the left sole supports: the CoM, between the feet, is outside it
    support = ctx.support.copy()
    support[:, 1] = False
    out = balance(replace(ctx, support=support))
    assert both > 0.02 and out["min_com_margin_m"] < 0 and not out["ok"]


def test_a_sole_rolling_over_its_toe_edge_does_not_slip(op3):
    """The left heel rises about the toe edge (0.4 rad in 1 s): the toe edge stays put, the
    heel leaves the floor, nothing planted moves. Dragging the planted outer toe corner sideways
    at 10 cm/s while rolling fails."""
    ctx = ctx_of(op3, examples.standing(op3, seconds=1.0).qpos)
    c0 = ctx.kin.corners[0, 0]                                 # front-left, front-right, back-right, back-left
    toe = 0.5 * (c0[0] + c0[1])
    fwd = toe - 0.5 * (c0[2] + c0[3])
    length = np.linalg.norm(fwd[:2])
    fwd = fwd / np.linalg.norm(fwd)
    theta = np.linspace(0.0, 0.4, ctx.kin.num_frames)
    rolled = np.repeat(ctx.kin.corners[:1], ctx.kin.num_frames, axis=0)
    for k in (2, 3):  # heel corners: on an arc about the toe edge
        side = c0[k] - (c0[k] - toe) @ fwd * fwd - toe      # sideways offset from the toe's centre line
        rolled[:, 0, k] = toe + side - length * np.cos(theta)[:, None] * fwd
        rolled[:, 0, k, 2] = c0[k, 2] + length * np.sin(theta)
    out = ground(replace(ctx, kin=replace(ctx.kin, corners=rolled)))
    assert out["ok"] and out["slipping"] == [] and out["skimming"] == []
    dragged = rolled.copy()  # 2 mm per frame at 50 fps
    dragged[:, 0, 0, :2] += np.outer(np.arange(len(dragged)) * 0.002, [fwd[1], -fwd[0]])
    out = ground(replace(ctx, kin=replace(ctx.kin, corners=dragged)))
    assert not out["ok"] and out["slipping"][0]["point"] == "outer toe corner"
    assert out["slipping"][0]["speed_m_s"] == pytest.approx(0.1, rel=0.01)

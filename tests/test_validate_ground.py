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
    assert out["penetrations"] == [] and out["skating"] == [] and out["non_foot_contacts"] == []


def test_sinking_into_the_floor_fails_with_the_depth(op3):
    q = examples.standing(op3).qpos.copy()
    q[20:30, 2] -= 0.02
    out = ground(ctx_of(op3, q))
    assert not out["ok"] and out["frames"] == list(range(20, 30))
    names = {v["body"] for v in out["penetrations"]}
    assert names == {"left foot", "right foot"}
    assert out["max_penetration_m"] == pytest.approx(0.02, abs=2e-3)


def test_feet_sliding_on_the_floor_is_skating(op3):
    q = examples.standing(op3).qpos.copy()
    q[:, 0] += 0.4 * np.arange(len(q)) / 50.0  # the whole robot glides at 0.4 m/s
    out = ground(ctx_of(op3, q))
    assert not out["ok"] and {v["foot"] for v in out["skating"]} == {"left", "right"}
    assert out["skating"][0]["speed_m_s"] == pytest.approx(0.4, rel=0.02)
    assert out["max_penetration_m"] < 1e-3


def test_contact_labels_decide_skating_from_a_low_swing(op3):
    """With labels, a foot moving fast just above the floor while labelled in the air is a low
    swing (scuff risk, not a verdict); the same foot labelled in contact is skating."""
    q = examples.standing(op3).qpos.copy()
    q[:, 0] += 0.4 * np.arange(len(q)) / 50.0
    swing = np.zeros((len(q), 2), dtype=bool)
    swing_out = ground(ctx_of(op3, q, meta={"contacts": swing.tolist()}))
    assert swing_out["ok"] and swing_out["skating"] == []
    assert swing_out["low_swing_frames"] and swing_out["low_swing_frames"][0] <= 2
    stance = ~swing
    stance_out = ground(ctx_of(op3, q, meta={"contacts": stance.tolist()}))
    assert not stance_out["ok"] and {v["foot"] for v in stance_out["skating"]} == {"left", "right"}


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

"""self_collision: neighbours and designed overlaps ignored, real collisions found."""

from __future__ import annotations

import pytest

from motion2robot.robot import load_robot
from motion2robot.validate import examples
from motion2robot.validate.collision import ignored_body_pairs, self_collision
from motion2robot.validate.context import prepare
from motion2robot.validate.models import body_name, check_model
from motion2robot.validate.options import CheckOptions


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def test_neighbours_are_ignored_but_not_distant_bodies(op3):
    m = check_model(op3)
    names = {tuple(sorted((body_name(m, a), body_name(m, b)))) for a, b in ignored_body_pairs(op3)}
    assert ("l_hip_pitch_link", "l_knee_link") in names
    assert ("l_el_link", "l_sho_roll_link") in names
    assert ("body_link", "l_el_link") not in names
    assert ("l_knee_link", "r_knee_link") not in names


def test_standing_has_no_self_collision(op3):
    out = self_collision(prepare(examples.standing(op3), op3, CheckOptions()))
    assert out["ok"] and out["violations"] == [] and out["frames"] == []


def test_depth_threshold_decides(op3):
    ctx = prepare(examples.arm_through_torso(op3), op3, CheckOptions())
    deep = self_collision(ctx)
    assert not deep["ok"]
    tolerant = self_collision(prepare(examples.arm_through_torso(op3), op3,
                                      CheckOptions(collision_depth=deep["max_depth_m"] + 0.001)))
    assert tolerant["ok"] and tolerant["max_depth_m"] == deep["max_depth_m"]

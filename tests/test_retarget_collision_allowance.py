"""The retargeter's capsule pairs come closer than touching only by what their capsules provably
overstate the geometry: a pair whose capsules are both fitted to their bodies gets no allowance,
whatever the nominal posture shows (the drafted Talos' shins went 4.7 mm into each other under an
allowance of 9.9 mm that the nominal posture's 14.5 mm overstatement seemed to justify)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from motion2robot.retarget.collision import BodyCapsule, collision_pairs, overstatement
from motion2robot.retarget.polytope import BodyPolytope
from motion2robot.robot import load_robot
from tests._shared import MENAGERIE, requires_menagerie


def _sphere_model() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><body name="b"><geom type="sphere" size="0.05" pos="0 0 0.1"/>'
        '<geom type="box" size="0.02 0.02 0.02"/></body></worldbody></mujoco>')


def test_overstatement_is_the_margin_over_the_farthest_geometry():
    m = _sphere_model()
    seg = (np.zeros(3), np.array([0.0, 0.0, 0.1]))
    # the sphere (radius 5 cm, points pushed out by 3 % to hold it) is the farthest from the segment
    tight = 0.05 * 1.03
    assert overstatement(m, BodyCapsule(1, *seg, tight)) == pytest.approx(0.0, abs=1e-9)
    assert overstatement(m, BodyCapsule(1, *seg, tight + 0.01)) == pytest.approx(0.01, abs=1e-9)
    assert overstatement(m, BodyCapsule(1, *seg, 0.03)) < 0  # inscribed: does not hold the sphere


def _allowances_are_proven(robot) -> list:
    pairs = [p for p in collision_pairs(robot) if not isinstance(p.b, BodyPolytope)]
    for p in pairs:
        assert p.allowance <= max(0.0, overstatement(robot.model, p.a) + overstatement(robot.model, p.b)) + 1e-12, p.name
    return pairs


def test_op3_pairs_get_only_the_allowance_their_capsules_prove():
    load_robot.cache_clear()
    pairs = _allowances_are_proven(load_robot("op3"))
    # the hips are 12.5 mm apart in capsules at the nominal posture, 24 mm in their boxes: the
    # capsules are tight on some side, so they are kept apart as they are
    hips = [p for p in pairs if "hip_roll" in p.name and p.name.count("hip_roll") == 2]
    assert hips and all(p.allowance < 1e-6 for p in hips)


@requires_menagerie
def test_drafted_talos_shins_get_no_allowance(monkeypatch, tmp_path):
    from motion2robot.robot.draft import draft_config, write_draft

    monkeypatch.setenv("MENAGERIE_ROOT", str(MENAGERIE))
    load_robot.cache_clear()
    robot = load_robot(str(write_draft(draft_config("menagerie:pal_talos", name="talos_draft"), tmp_path / "t.toml")))
    pairs = {p.name: p for p in _allowances_are_proven(robot)}
    shins = pairs["leg_left_4_link-leg_right_4_link"]
    assert shins.allowance < 1e-6
    load_robot.cache_clear()

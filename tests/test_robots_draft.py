"""``robots init``: drafted configs load, find the skeleton, and agree with the hand-written H1 config."""

import math
import sys

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motion2robot.errors import RobotConfigError
from motion2robot.robot import load_robot
from motion2robot.robot.body_geometry import axes_center
from motion2robot.robot.describe import compare_robots
from motion2robot.robot.config import load_config
from motion2robot.robot.draft import draft_config, write_draft
from motion2robot.robot.draft_toml import value
from tests._shared import MOTIONS, requires_menagerie, requires_shared

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib



def _draft_and_load(model, tmp_path, name="bot"):
    draft = draft_config(model, name=name)
    path = write_draft(draft, tmp_path / f"{name}.toml")
    return draft, load_robot(str(path))


@requires_menagerie
@pytest.mark.parametrize("name, dof", [("unitree_h1", 19), ("unitree_g1", 29), ("robotis_op3", 20)])
def test_menagerie_drafts_load_and_stand(menagerie_env, tmp_path, name, dof):
    draft, r = _draft_and_load(f"menagerie:{name}", tmp_path, name)
    assert r.n_joints == dof and len(r.keypoints) == 18
    assert r.config.menagerie == name
    d = r.new_data()
    assert np.all(np.abs(d.site_xpos[r.sole_sites.ravel(), 2]) < 0.002)
    mujoco.mj_forward(r.model, d)
    assert d.ncon == 0
    assert not [c for c in draft.checks if "flat" in c or "self-contact" in c]
    assert any("velocity" in c for c in draft.checks)  # an MJCF never has velocity limits


@requires_menagerie
def test_op3_without_ranges_gets_flagged_guesses(menagerie_env, tmp_path):
    draft, r = _draft_and_load("menagerie:robotis_op3", tmp_path, "op3")
    text = (tmp_path / "op3.toml").read_text()
    assert np.allclose(r.lower, -1.5) and np.allclose(r.upper, 1.5)
    assert text.count('reason = "CHECK') == 20
    assert any("no range" in c for c in draft.checks) and any("wrist" in c for c in draft.checks)
    # torque from the position actuators' forcerange (+-5), kp from their gain (21.1)
    assert np.allclose(r.torque_limit, 5.0) and np.allclose(r.kp, 21.1)
    # knees bent the human way: the knee ahead of the ankle
    d = r.new_data()
    p = {k: d.site_xpos[s] for k, s in zip(r.keypoints, r.keypoint_sites)}
    for side in ("left", "right"):
        assert p[f"{side}_knee"][0] > p[f"{side}_ankle"][0] + 0.01


@requires_menagerie
def test_h1_draft_matches_the_hand_written_config(menagerie_env, tmp_path):
    """Same keypoint bodies; keypoints within 2.5 cm at the shipped nominal pose (the pelvis aside);
    soles within 1 cm."""
    _, drafted = _draft_and_load("menagerie:unitree_h1", tmp_path, "h1draft")
    shipped = load_robot("menagerie:unitree_h1")
    gaps, soles = compare_robots(drafted, shipped)
    assert len(gaps) == len(shipped.keypoints) == 18
    assert all(g.body_a == g.body_b for g in gaps), [g for g in gaps if g.body_a != g.body_b]
    assert max(g.gap for g in gaps if g.human != "pelvis") < 0.025, gaps
    # the draft's pelvis is the hip centres' midpoint; the hand-written config keeps the root origin
    pelvis = next(g for g in gaps if g.human == "pelvis")
    assert 0.15 < pelvis.gap < 0.2
    assert max(soles) < 0.01
    assert drafted.config.torso_body == shipped.config.torso_body and drafted.config.root_body == shipped.config.root_body
    assert np.allclose(drafted.torque_limit, shipped.torque_limit)
    assert drafted.height == pytest.approx(shipped.height, abs=0.02)


@requires_menagerie
def test_compare_refuses_different_models(menagerie_env):
    with pytest.raises(RobotConfigError, match="not the same model"):
        compare_robots(load_robot("op3"), load_robot("menagerie:unitree_h1"))


# A humanoid with generic names (no knee/elbow/head in any name), unlimited hips and box feet.
GENERIC = """
<mujoco model="generic">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base" pos="0 0 0.9">
      <freejoint/>
      <geom type="box" size="0.08 0.12 0.1"/>
      {legs}
      <body name="upper" pos="0 0 0.15">
        <joint name="waist" axis="0 0 1" range="-1 1"/>
        <geom type="box" size="0.08 0.15 0.15" pos="0 0 0.15"/>
        <body name="top" pos="0 0 0.4"><joint name="nod" axis="0 1 0" range="-0.5 0.5"/>
          <geom type="sphere" size="0.09" pos="0 0 0.1"/></body>
        {arms}
      </body>
    </body>
  </worldbody>
  <actuator>{motors}</actuator>
</mujoco>
"""
LEG = """
      <body name="{s}1" pos="0 {y} -0.15"><joint name="{s}_j1" axis="0 0 1"/>{inertial}
        <body name="{s}2"><joint name="{s}_j2" axis="1 0 0" range="-0.5 0.5"/>{inertial}
          <body name="{s}3"><joint name="{s}_j3" axis="0 1 0" range="-1.5 0.5"/>
            <geom type="capsule" fromto="0 0 0 0 0 -0.35" size="0.04"/>
            <body name="{s}4" pos="0 0 -0.35"><joint name="{s}_j4" axis="0 1 0" range="0 2"/>
              <geom type="capsule" fromto="0 0 0 0 0 -0.33" size="0.035"/>
              <body name="{s}5" pos="0 0 -0.35"><joint name="{s}_j5" axis="0 1 0" range="-0.8 0.8"/>
                <geom type="box" size="0.09 0.045 0.02" pos="0.03 0 -0.03"/>
              </body></body></body></body></body>"""
ARM = """
        <body name="{s}a1" pos="0 {y} 0.28"><joint name="{s}_a1" axis="0 1 0" range="-2 2"/>{inertial}
          <body name="{s}a2"><joint name="{s}_a2" axis="1 0 0" range="-1.5 1.5"/>
            <geom type="capsule" fromto="0 0 0 0 0 -0.25" size="0.03"/>
            <body name="{s}a3" pos="0 0 -0.25"><joint name="{s}_a3" axis="0 1 0" range="-2 0"/>
              <geom type="capsule" fromto="0 0 0 0 0 -0.22" size="0.025"/>
              <geom type="sphere" pos="0 0 -0.24" size="0.03"/>
            </body></body></body>"""


@pytest.fixture
def generic_mjcf(tmp_path):
    inertial = '<inertial pos="0 0 0" mass="0.3" diaginertia="1e-3 1e-3 1e-3"/>'
    legs = LEG.format(s="p", y=0.1, inertial=inertial) + LEG.format(s="q", y=-0.1, inertial=inertial)
    arms = ARM.format(s="u", y=0.22, inertial=inertial) + ARM.format(s="v", y=-0.22, inertial=inertial)
    motors = "".join(f'<motor joint="{s}_j{i}" ctrlrange="-30 30"/>' for s in "pq" for i in range(1, 6))
    xml = tmp_path / "model" / "generic.xml"
    xml.parent.mkdir()
    xml.write_text(GENERIC.format(legs=legs, arms=arms, motors=motors))
    return xml


def test_generic_humanoid_by_geometry(generic_mjcf, tmp_path):
    out = tmp_path / "cfg"
    out.mkdir()
    draft, r = _draft_and_load(str(generic_mjcf), out, "generic")
    text = (out / "generic.toml").read_text()
    assert 'mjcf = "../model/generic.xml"' in text  # relative to the TOML
    kp = {k.human: k.body for k in r.config.keypoints}
    assert kp["left_knee"] == "p4" and kp["right_knee"] == "q4"  # left = +y
    assert kp["left_ankle"] == "p5" and kp["left_elbow"] == "ua3" and kp["right_elbow"] == "va3"
    assert kp["head"] == "top" and r.config.torso_body == "upper"
    # hip: the three hinge axes meet at p1's origin
    hip = next(k for k in r.config.keypoints if k.human == "left_hip")
    d = r.new_data()
    hip_w = d.site_xpos[r.keypoint_sites[r.keypoints.index("left_hip")]]
    assert np.allclose(hip_w, d.xpos[r.model.body("p1").id], atol=1e-3), hip
    # sole: the foot box bottom, 0.18 x 0.09 at z -0.05 in p5
    foot = r.config.feet[0]
    assert foot.body == "p5" and foot.sole_center == pytest.approx((0.03, 0.0, -0.05)) and foot.sole_half == pytest.approx((0.09, 0.045))
    # unlimited hip yaw: drafted +-1.5 and flagged; leg torques from the motors, arms default (median)
    assert r.config.joint("p_j1").range == (-1.5, 1.5) and "CHECK" in r.config.joint("p_j1").reason
    assert r.torque_limit[r.joint_index("p_j4")] == 30.0
    assert any("knee" in c for c in draft.checks)  # the knee by position; the elbow from the arm's axes
    elbow = next(k for k in draft.keypoints if k.human == "left_elbow")
    assert "u_a3" in elbow.note and "CHECK" not in elbow.note
    assert any("head" in g and "top" in g for g in draft.guesses) or any("head" in c for c in draft.checks)
    # knees bent 0.3 (j4 axis +y), hip and ankle -0.15
    assert draft.nominal["p_j4"] == 0.3 and draft.nominal["p_j3"] == -0.15 and draft.nominal["p_j5"] == -0.15
    # no hand joints: the wrist sits near the forearm tip
    wrist = next(k for k in r.config.keypoints if k.human == "left_wrist")
    assert wrist.body == "ua3" and -0.27 < wrist.offset[2] < -0.2


@pytest.mark.parametrize("xml, needle", [
    ("<mujoco><worldbody><body name='b'><joint type='hinge'/><geom size='0.1'/></body></worldbody></mujoco>",
     "needs exactly one free joint"),
    ("<mujoco><worldbody><body name='b'><freejoint/><geom size='0.1'/><body name='c'><joint type='ball'/>"
     "<geom size='0.1'/></body></body></worldbody></mujoco>", "is not a hinge"),
    ("<mujoco><worldbody><body name='b'><freejoint/><geom size='0.1'/><body name='c' pos='0 0.1 0.5'>"
     "<joint axis='1 0 0'/><geom size='0.1'/></body></body></worldbody></mujoco>", "cannot find a left foot"),
    ("<mujoco><worldbody><bogus/></worldbody></mujoco>", "MuJoCo cannot read this MJCF"),
])
def test_not_a_humanoid(tmp_path, xml, needle):
    p = tmp_path / "x.xml"
    p.write_text(xml)
    with pytest.raises(RobotConfigError) as e:
        draft_config(str(p))
    assert needle in str(e.value) and "\n" not in str(e.value)


def test_missing_model(tmp_path):
    with pytest.raises(RobotConfigError, match="MJCF not found"):
        draft_config(str(tmp_path / "nope.xml"))


def test_axes_center_finds_where_lines_meet():
    c = np.array([1.5, 2.5, 3.5])
    d = np.eye(3)[[1, 2, 0]]  # along y, z, x
    p = c + d * np.array([[7.0], [-2.0], [4.0]])  # anchors elsewhere on the three lines through c
    assert np.allclose(axes_center(p, d, prior=np.zeros(3)), c, atol=1e-4)
    # skew lines: the midpoint of their common perpendicular
    skew = axes_center(np.array([[0, 0, 0.0], [0, 0, 1.0]]), np.eye(3)[[0, 1]], prior=np.zeros(3))
    assert np.allclose(skew, [0, 0, 0.5], atol=1e-4)
    # a single line: the prior picks the point on it
    assert np.allclose(axes_center(p[:1], d[:1], prior=np.array([1.0, 5.0, 1.0])), [1.5, 5, 3.5], atol=1e-3)


@settings(max_examples=60, deadline=None)
@given(st.dictionaries(st.text(min_size=1, max_size=8),
                       st.one_of(st.text(max_size=12), st.floats(allow_nan=False, allow_infinity=False, width=32),
                                 st.integers(-10**6, 10**6), st.lists(st.floats(-1e3, 1e3), max_size=3)),
                       min_size=1, max_size=4))
def test_toml_values_round_trip(table):
    from motion2robot.robot.draft_toml import key

    text = "\n".join(f"{key(k)} = {value(v)}" for k, v in table.items())
    back = tomllib.loads(text)
    assert set(back) == set(table)
    for k, v in table.items():
        if isinstance(v, float):
            assert math.isclose(back[k], round(v, 6), rel_tol=1e-9, abs_tol=1e-12)
        elif isinstance(v, list):
            assert back[k] == pytest.approx([round(x, 6) for x in v])
        else:
            assert back[k] == v


@requires_menagerie
def test_written_draft_is_a_valid_config_file(menagerie_env, tmp_path):
    draft = draft_config("menagerie:unitree_g1", name="g1d")
    cfg = load_config(write_draft(draft, tmp_path / "g1d.toml"))
    assert cfg.name == "g1d" and cfg.menagerie == "unitree_g1" and cfg.entry == "g1"
    assert {k.human for k in cfg.keypoints} >= {"pelvis", "left_wrist", "right_foot", "head"}


@requires_shared
@requires_menagerie
def test_retargeter_runs_on_drafts(menagerie_env, tmp_path, generic_mjcf):
    """A drafted config is good enough for the retargeter: a real clip retargets onto the drafted H1
    about as well as onto the shipped one, and onto the generic humanoid within its limits."""
    from motion2robot.motion import read_motion
    from motion2robot.motion.ops import trim
    from motion2robot.retarget import RetargetOptions, whole_body as retarget

    human = trim(read_motion(MOTIONS / "humanml3d_joints" / "007005.npy")[0], 0, 10)
    opts = RetargetOptions(backend="vm", iterations=(4, 3))
    _, drafted = _draft_and_load("menagerie:unitree_h1", tmp_path, "h1draft")
    _, generic = _draft_and_load(str(generic_mjcf), tmp_path, "generic")
    res = {}
    for r in (drafted, load_robot("menagerie:unitree_h1"), generic):
        out = retarget(human, r, opts)
        q = out.qpos[:, 7:]
        assert out.qpos.shape == (10, r.nq) and np.isfinite(out.qpos).all()
        assert np.all(q >= r.lower - 1e-6) and np.all(q <= r.upper + 1e-6)
        res[r.name] = out.meta["solver"]["max_residual"]
    # The draft places the hips 2 cm from the hand-written config (least-squares meeting point of the
    # hip axes) and keeps 5 rad/s speed limits: allow 5 cm more worst-frame error than the shipped
    # config, far less than a wrong keypoint map gives (tens of centimetres).
    assert res[drafted.name] <= res["menagerie:unitree_h1"] + 0.05, res

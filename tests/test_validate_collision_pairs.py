"""Self-collision pairs as MuJoCo sees them: the shared filter matches mj_collision, a pair the old
"nearest collidable ancestor" rule dropped is judged, nominal overlaps count only by their deepening."""

from __future__ import annotations

from types import SimpleNamespace

import mujoco
import numpy as np
import pytest

from motion2robot.robot import collision_filter as cf
from motion2robot.robot.config import parse_config
from motion2robot.robot.loader import build_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate.collision import ignored_body_pairs, self_collision
from motion2robot.validate.kinematics import compute_kinematics
from motion2robot.validate.options import CheckOptions
from motion2robot.validate.reasons import reasons

# pelvis box; a geometry-less waist-yaw link, then the torso (box) on a roll hinge: MuJoCo tests
# pelvis/torso (the torso's parent weld body is the yaw link, not the pelvis).
# "arm" overlaps the torso at the nominal pose by 10 mm (the model itself overlaps there).
TRUNK = """
<mujoco>
  <option {option}/>
  <worldbody>
    <body name="pelvis" pos="0 0 0.5">
      <freejoint/>
      <geom name="pelvis_box" type="box" size="0.1 0.15 0.05"/>
      <body name="waist_yaw" pos="0 0 0.1"><joint name="yaw" axis="0 0 1" range="-1 1"/>
        <inertial pos="0 0 0" mass="0.1" diaginertia="1e-3 1e-3 1e-3"/>
        <body name="torso" pos="0 0 0.05"><joint name="roll" axis="1 0 0" range="-1 1"/>
          <geom name="torso_box" type="box" size="0.1 0.15 0.1" pos="0 0 0.1" {torso_bits}/>
          <body name="arm" pos="0 0.24 0.1"><joint name="arm" axis="1 0 0" range="-1 1"/>
            <geom name="arm_box" type="box" size="0.03 0.1 0.03" pos="0 0 0"/>
          </body>
        </body>
      </body>
      <body name="lfoot" pos="0 0.1 -0.45"><joint name="lf" axis="0 1 0" range="-1 1"/>
        <geom type="box" size="0.08 0.04 0.02"/></body>
      <body name="rfoot" pos="0 -0.1 -0.45"><joint name="rf" axis="0 1 0" range="-1 1"/>
        <geom type="box" size="0.08 0.04 0.02"/></body>
    </body>
  </worldbody>
  {contact}
</mujoco>
"""


def _robot(tmp_path, option="", torso_bits="", contact=""):
    xml = tmp_path / f"trunk{abs(hash((option, torso_bits, contact)))}.xml"
    xml.write_text(TRUNK.format(option=option, torso_bits=torso_bits, contact=contact))
    cfg = parse_config({
        "name": "trunk", "model": {"mjcf": str(xml), "root_body": "pelvis", "torso_body": "torso"},
        "keypoints": {"pelvis": {"body": "pelvis"}, "head": {"body": "torso", "offset": [0, 0, 0.2]}},
        "feet": {s: {"body": f"{s[0]}foot", "sole_center": [0, 0, -0.02], "sole_half": [0.08, 0.04]}
                 for s in ("left", "right")}})
    return build_robot(cfg, xml, name=f"trunk-{abs(hash((option, torso_bits, contact)))}")


def _check(robot, q):
    motion = RobotMotion(q, 50.0, robot.joint_names, robot.name, meta={"robot_hash": robot.model_hash})
    ctx = SimpleNamespace(kin=compute_kinematics(motion, robot), robot=robot, options=CheckOptions())
    return self_collision(ctx)


def _mujoco_depth(robot, q, g1, g2):
    d = mujoco.MjData(robot.model)
    d.qpos[:] = q
    mujoco.mj_forward(robot.model, d)
    a, b = (mujoco.mj_name2id(robot.model, mujoco.mjtObj.mjOBJ_GEOM, n) for n in (g1, g2))
    return max((-c.dist for c in d.contact[:d.ncon] if {int(c.geom[0]), int(c.geom[1])} == {a, b}), default=0.0)


def _roll_for_depth(robot, depth):
    """qpos rolling the torso until MuJoCo's own torso/pelvis depth is ``depth`` (m)."""
    q = robot.nominal_qpos.copy()
    i = 7 + robot.joint_names.index("roll")
    for angle in np.linspace(0, 1, 2001):
        q[i] = angle
        if _mujoco_depth(robot, q, "torso_box", "pelvis_box") >= depth:
            return q
    raise AssertionError("no roll reaches that depth")


@pytest.mark.parametrize("option, contact", [
    ("", ""),
    ('<flag filterparent="disable"/>', ""),
    ("", '<contact><exclude body1="pelvis" body2="torso"/><pair geom1="arm_box" geom2="pelvis_box"/></contact>'),
])
def test_filter_matches_mujoco_when_everything_overlaps(tmp_path, option, contact):
    """Every geom a big sphere at one point: MuJoCo's contacts are exactly the pairs it tests."""
    opt = option.replace("<flag", "").replace("/>", "") if option else ""
    xml = TRUNK.format(option="", torso_bits='contype="2" conaffinity="3"', contact=contact)
    spec = mujoco.MjSpec.from_string(xml.replace("<option />", f"<option>{option}</option>" if opt else ""))
    for g in spec.geoms:
        g.type, g.size, g.pos = mujoco.mjtGeom.mjGEOM_SPHERE, [5, 0, 0], [0, 0, 0]
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    got = {tuple(sorted(map(int, c.geom))) for c in d.contact[:d.ncon]}
    want = {(int(a), int(b)) for a, b in zip(*np.nonzero(np.triu(cf.tested_geom_pairs(m), 1)))}
    assert got == want and got


def test_torso_pelvis_pair_across_a_bare_link_is_judged(tmp_path):
    robot = _robot(tmp_path)
    m = robot.model
    ids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, n) for n in ("pelvis", "torso", "waist_yaw", "arm")]
    pelvis, torso, yaw, arm = ids
    assert (pelvis, torso) in cf.tested_body_pairs(m)
    assert (torso, arm) not in cf.tested_body_pairs(m)  # parent and child: MuJoCo's filterparent
    q = _roll_for_depth(robot, 0.024)
    out = _check(robot, np.stack([robot.nominal_qpos, q, robot.nominal_qpos]))
    assert not out["ok"] and out["frames"] == [1]
    v = out["violations"][0]
    assert {v["body1"], v["body2"]} == {"pelvis", "torso"} and "nominal_depth_m" not in v
    assert v["depth_m"] == pytest.approx(_mujoco_depth(robot, q, "torso_box", "pelvis_box"), abs=1e-4)
    assert v["depth_m"] >= 0.024


def test_bitmasks_and_excludes_drop_exactly_what_mujoco_drops(tmp_path):
    q = _roll_for_depth(_robot(tmp_path), 0.024)
    for kwargs in ({"torso_bits": 'contype="2" conaffinity="2"'},  # 2&1 = 0: never tested
                   {"contact": '<contact><exclude body1="pelvis" body2="torso"/></contact>'}):
        robot = _robot(tmp_path, **kwargs)
        pair = tuple(sorted(mujoco.mj_name2id(robot.model, mujoco.mjtObj.mjOBJ_BODY, n) for n in ("pelvis", "torso")))
        assert pair not in cf.tested_body_pairs(robot.model)
        out = _check(robot, np.stack([robot.nominal_qpos, q]))
        assert not any({v["body1"], v["body2"]} == {"pelvis", "torso"} for v in out["violations"]), out


def test_nominal_overlap_reported_and_judged_by_its_deepening(tmp_path):
    robot = _robot(tmp_path)
    nominal = _mujoco_depth(robot, robot.nominal_qpos, "arm_box", "torso_box")
    assert nominal == 0.0  # arm is the torso's child: filterparent drops the pair
    # move the arm so that it overlaps the pelvis at the nominal pose: a geom pair MuJoCo tests
    xml = TRUNK.format(option="", torso_bits="", contact="").replace('<body name="arm" pos="0 0.24 0.1">',
                                                                       '<body name="arm" pos="0 0.2 -0.085">')
    path = tmp_path / "overlap.xml"
    path.write_text(xml)
    cfg = parse_config({
        "name": "ov", "model": {"mjcf": str(path), "root_body": "pelvis", "torso_body": "torso"},
        "keypoints": {"pelvis": {"body": "pelvis"}},
        "feet": {s: {"body": f"{s[0]}foot", "sole_center": [0, 0, -0.02], "sole_half": [0.08, 0.04]}
                 for s in ("left", "right")}})
    robot = build_robot(cfg, path, name="overlap")
    base = _mujoco_depth(robot, robot.nominal_qpos, "arm_box", "pelvis_box")
    assert base > 0.005
    m = robot.model
    pair = tuple(sorted(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, n) for n in ("arm", "pelvis")))
    assert pair in ignored_body_pairs(robot)
    out = _check(robot, np.tile(robot.nominal_qpos, (3, 1)))
    assert out["ok"] and out["max_depth_m"] == 0.0
    assert out["nominal_overlaps"] == [{"body1": "pelvis", "body2": "arm", "nominal_depth_m": round(base, 4)}]
    # the arm pushed down into the pelvis: only the extra depth counts
    q = robot.nominal_qpos.copy()
    i = 7 + robot.joint_names.index("arm")
    for angle in np.linspace(0, 1, 1001):
        q[i] = angle
        if _mujoco_depth(robot, q, "arm_box", "pelvis_box") > base + 0.015:
            break
    deeper = _mujoco_depth(robot, q, "arm_box", "pelvis_box")
    out = _check(robot, np.stack([robot.nominal_qpos, q]))
    v = out["violations"][0]
    assert not out["ok"] and v["nominal_depth_m"] == round(base, 4)
    assert v["depth_m"] == pytest.approx(deeper - base, abs=2e-4)
    text = " ".join(reasons({"self_collision": out}, 50.0))
    assert "the model itself overlaps them" in text and "deeper" in text

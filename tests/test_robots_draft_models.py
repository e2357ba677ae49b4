"""``robots init`` on the awkward models real humanoids are: empty toe markers, tilted foot frames,
collision geoms marked by group instead of contype, no arms; and bad input, one line, exit 2."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.robot import load_robot
from motion2robot.robot.draft import draft_config, write_draft
from tests._shared import MOTIONS, requires_shared
from tests.test_robots_draft import ARM, GENERIC, LEG

INERTIAL = '<inertial pos="0 0 0" mass="0.3" diaginertia="1e-3 1e-3 1e-3"/>'
FOOT = '<geom type="box" size="0.09 0.045 0.02" pos="0.03 0 -0.03"/>'


def _model(tmp_path, name="bot", foot=FOOT, arms=True, defaults="", leg_edit=lambda s: s):
    legs = "".join(leg_edit(LEG.format(s=s, y=y, inertial=INERTIAL).replace(FOOT, foot.format(s=s)))
                   for s, y in (("p", 0.1), ("q", -0.1)))
    arm = (ARM.format(s="u", y=0.22, inertial=INERTIAL) + ARM.format(s="v", y=-0.22, inertial=INERTIAL)) if arms else ""
    motors = "".join(f'<motor joint="{s}_j{i}" ctrlrange="-30 30"/>' for s in "pq" for i in range(1, 6))
    xml = GENERIC.format(legs=legs, arms=arm, motors=motors)
    if defaults:
        xml = xml.replace('<compiler angle="radian"/>', f'<compiler angle="radian"/><default>{defaults}</default>')
    path = tmp_path / f"{name}.xml"
    path.write_text(xml)
    return path


def _load(draft, tmp_path):
    load_robot.cache_clear()
    return load_robot(str(write_draft(draft, tmp_path / f"{draft.name}.toml")))


def _flat(robot) -> float:
    """Largest |height| (m) of the sole corners at the nominal pose."""
    return float(np.abs(robot.new_data().site_xpos[robot.sole_sites.ravel(), 2]).max())


def test_empty_toe_marker_steps_up_to_the_foot(tmp_path):
    xml = _model(tmp_path, foot=FOOT + '<body name="{s}toe" pos="0.12 0 -0.05"/>')
    draft = draft_config(str(xml), name="toe")
    assert [f.body for f in draft.feet] == ["p5", "q5"]
    assert any("ptoe has no collision geometry" in g for g in draft.guesses)
    robot = _load(draft, tmp_path)
    assert _flat(robot) < 1e-3


def test_tilted_foot_frame_sole_in_the_floor_plane(tmp_path):
    """A foot body pitched 0.3 rad (17 deg) whose box is level in the world: the sole is found level."""
    tilted = '<geom type="box" size="0.09 0.045 0.02" pos="0.03 0 -0.03" euler="0 -0.3 0"/>'
    xml = _model(tmp_path, foot=tilted, leg_edit=lambda s: s.replace('5" pos="0 0 -0.35">', '5" pos="0 0 -0.35" euler="0 0.3 0">'))
    draft = draft_config(str(xml), name="tilt")
    assert draft.feet[0].sole_quat is not None
    assert draft.feet[0].sole_half == pytest.approx((0.09, 0.045), abs=1e-3)
    robot = _load(draft, tmp_path)
    assert _flat(robot) < 1e-3  # all 8 corners on the floor, none sunk


def test_collision_geoms_marked_by_group_not_contype(tmp_path):
    """contype 0 everywhere (collision geoms in group 3): the sole comes from the group-3 box, not
    from the bigger visual box (group 2) below it."""
    visual = FOOT + '<geom type="box" size="0.12 0.06 0.04" pos="0.03 0 -0.03" group="2"/>'
    xml = _model(tmp_path, foot=visual, defaults='<geom contype="0" conaffinity="0" group="3"/>')
    draft = draft_config(str(xml), name="groups")
    foot = draft.feet[0]
    assert foot.sole_center[2] == pytest.approx(-0.05, abs=1e-4) and foot.sole_half == pytest.approx((0.09, 0.045))
    assert not any("visual" in c for c in draft.checks)


@requires_shared
def test_legs_only_robot_drafts_and_retargets(tmp_path):
    from motion2robot.motion import read_motion
    from motion2robot.motion.ops import trim
    from motion2robot.retarget import RetargetOptions, retarget

    xml = _model(tmp_path, arms=False)
    draft = draft_config(str(xml), name="legs")
    humans = {k.human for k in draft.keypoints}
    assert {"pelvis", "left_hip", "right_knee", "left_ankle", "right_foot"} <= humans
    assert not humans & {"left_shoulder", "right_elbow", "left_wrist"}
    assert any("legs-only" in g for g in draft.guesses)
    robot = _load(draft, tmp_path)
    human = trim(read_motion(MOTIONS / "humanml3d_joints" / "007005.npy")[0], 0, 10)
    out = retarget(human, robot, RetargetOptions(backend="vm", iterations=(3, 3)))
    q = out.qpos[:, 7:]
    assert np.isfinite(out.qpos).all() and np.all(q >= robot.lower - 1e-9) and np.all(q <= robot.upper + 1e-9)


def test_init_creates_the_output_folder_and_prints_keypoint_reasons(tmp_path, capsys):
    out = tmp_path / "new" / "deeper" / "bot.toml"
    assert main(["robots", "init", str(_model(tmp_path)), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert out.is_file()
    rows = {ln.split()[0]: ln for ln in text.split("keypoints:")[1].split("guessed:")[0].splitlines() if ln.strip()}
    assert "midpoint of the hip centres" in rows["pelvis"]
    assert "where the axes of u_a1, u_a2 meet" in rows["left_shoulder"]
    assert "where the axes of u_a3 meet" in rows["left_elbow"]


BAD = [
    ("nofeet", '<mujoco><worldbody><body name="pelvis" pos="0 0 1"><freejoint/><geom size="0.1"/>'
               '<body name="arm" pos="0 0.2 0.3"><joint axis="1 0 0"/><geom size="0.05"/></body></body></worldbody></mujoco>',
     ["cannot find a left foot", "root body pelvis", "must stand along z with x forward"]),
    ("nofloor", None, ["foot ptoe", "no collision geometry", "add a collision geom"]),
    ("nomesh", '<mujoco><asset><mesh name="foot" file="meshes/foot.stl"/></asset><worldbody><body name="b">'
               '<freejoint/><geom type="mesh" mesh="foot"/></body></worldbody></mujoco>',
     ["meshes/foot.stl", "cannot be read", "fix that path"]),
]


@pytest.mark.parametrize("name, xml, needles", BAD, ids=[b[0] for b in BAD])
def test_bad_models_one_line_exit_2(tmp_path, capsys, name, xml, needles):
    if xml is None:  # every foot geom visual only (contype 0 while other geoms collide)
        path = _model(tmp_path, name, foot='<geom type="box" size="0.09 0.045 0.02" pos="0.03 0 -0.03" contype="0" conaffinity="0"/>'
                      '<body name="{s}toe" pos="0.12 0 -0.05"/>')
        text = path.read_text().replace('<geom type="capsule" fromto="0 0 0 0 0 -0.33" size="0.035"/>',
                                        '<geom type="capsule" fromto="0 0 0 0 0 -0.33" size="0.035" contype="0" conaffinity="0"/>')
        text = text.replace('<geom type="capsule" fromto="0 0 0 0 0 -0.35" size="0.04"/>',
                            '<geom type="capsule" fromto="0 0 0 0 0 -0.35" size="0.04" contype="0" conaffinity="0"/>')
        path.write_text(text)
    else:
        path = tmp_path / f"{name}.xml"
        path.write_text(xml)
    assert main(["robots", "init", str(path), "-o", str(tmp_path / "out.toml")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err and err.startswith("motion2robot: error: ")
    for n in needles:
        assert n in err, err
    assert not (tmp_path / "out.toml").exists()


def test_unlimited_hinge_without_a_range_is_one_line_exit_2(tmp_path, capsys):
    """A config that leaves a rangeless hinge unset: the loader names the joint and the fix."""
    xml = _model(tmp_path, "norange")
    draft = draft_config(str(xml), name="norange")
    cfg = write_draft(draft, tmp_path / "norange.toml")
    text = cfg.read_text().replace('range = [-1.5, 1.5]\nreason = "CHECK: drafted guess, the model declares no range"\n', "", 1)
    cfg.write_text(text)
    load_robot.cache_clear()
    assert main(["robots", "show", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "p_j1 has no range" in err and "add [joints.p_j1] range" in err


def test_show_render_marks_the_keypoints(tmp_path, capsys):
    """``robots show --render``: a picture with the keypoint colours on it (offscreen GL)."""
    from PIL import Image

    from motion2robot.viz.keypoint_image import LEFT_RGBA, RIGHT_RGBA

    out = tmp_path / "op3.png"
    assert main(["robots", "show", "op3", "--render", str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    img = np.asarray(Image.open(out).convert("RGB")).astype(int)
    assert img.shape[1] > img.shape[0]  # front and side views
    for rgba in (LEFT_RGBA, RIGHT_RGBA):
        target = (np.asarray(rgba[:3]) * 255).astype(int)
        near = np.abs(img - target).sum(axis=2) < 90
        assert near.sum() > 20, rgba  # the balls of that side are drawn
    assert main(["robots", "show", "op3", "--render", str(tmp_path / "op3.gif")]) == 2

"""Edit pairs on the robot: hinges driven by unedited parts keep the source's robot motion exactly."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.edit import retarget_edit
from motion2robot.edit.compose import source_weights
from motion2robot.edit.parts import hinge_parts
from motion2robot.motion import read_motion
from motion2robot.motion.human import KP, HumanMotion
from tests._shared import MOTIONS, requires_shared


def test_blend_weights_are_exactly_one_beyond_the_blend() -> None:
    changed = np.zeros(30, bool)
    changed[10:15] = True
    w = source_weights(changed, 4)
    assert (w[:6] == 1.0).all() and (w[19:] == 1.0).all() and (w[10:15] == 0.0).all()
    assert np.all(np.diff(w[5:11]) <= 0) and np.all(np.diff(w[14:20]) >= 0)


def _rotate(p: np.ndarray, joints: list[int], pivot: int, ang: np.ndarray, axis: int) -> np.ndarray:
    p = p.copy()
    c, s = np.cos(ang), np.sin(ang)
    i, j = [(1, 2), (0, 2), (0, 1)][axis]
    for k in joints:
        d = p[:, k] - p[:, pivot]
        di, dj = c * d[:, i] - s * d[:, j], s * d[:, i] + c * d[:, j]
        p[:, k, i], p[:, k, j] = p[:, pivot, i] + di, p[:, pivot, j] + dj
    return p


def _bump(t: int, a: int, b: int, amp: float) -> np.ndarray:
    ang = np.zeros(t)
    ang[a:b + 1] = amp * np.sin(np.linspace(0, np.pi, b - a + 1))
    return ang


@pytest.fixture(scope="module")
def source() -> HumanMotion:
    if MOTIONS is None:
        pytest.skip("../shared is absent")
    return read_motion(MOTIONS / "humanml3d_joints" / "012314.npy")[0]


@pytest.fixture(scope="module")
def robot():
    from motion2robot.robot import load_robot
    return load_robot("op3")


@requires_shared
def test_right_arm_edit_keeps_every_other_joint_of_the_source(source, robot) -> None:
    arm = [KP["right_elbow"], KP["right_wrist"]]
    p = _rotate(source.positions, arm, KP["right_shoulder"], _bump(source.num_frames, 40, 80, 0.8), axis=0)
    r = retarget_edit(source, HumanMotion(p, source.fps, meta=dict(source.meta)), robot)
    assert set(r.human) == {"right_arm"}
    parts = hinge_parts(robot)
    q_s, q_e = r.source.qpos, r.edited.qpos
    blend, t_r = r.info["blend_frames"], r.info["robot_frames"]  # the tempo policy may slow the motion
    human_frame = np.rint(np.arange(t_r) * (source.num_frames - 1) / (t_r - 1))
    edited = np.flatnonzero((human_frame >= 40) & (human_frame <= 80))
    outside = np.flatnonzero(np.abs(np.arange(t_r)[:, None] - edited[None]).min(axis=1) > blend)
    for h, ps in enumerate(parts):
        d = np.abs(q_e[:, 7 + h] - q_s[:, 7 + h])
        if "right_arm" not in ps:
            assert d.max() <= 1e-6, robot.joint_names[h]  # leg, torso, left arm: all frames
        assert d[outside].max() <= 1e-6, robot.joint_names[h]
    assert np.abs(q_e[:, :7] - q_s[:, :7]).max() <= 1e-6  # root: the pelvis was not edited
    changed = {j for j in r.robot}
    assert changed and all(j.startswith("r_") and ("sho" in j or "el" in j) for j in changed)


@requires_shared
def test_leg_edit_changes_the_legs(source, robot) -> None:
    leg = [KP["left_knee"], KP["left_ankle"], KP["left_foot"]]
    p = _rotate(source.positions, leg, KP["left_hip"], _bump(source.num_frames, 40, 80, 0.6), axis=1)
    from motion2robot.retarget import RetargetOptions

    whole = RetargetOptions(tempo="human", legs="whole")  # the policy would hold a stance for this clip
    r = retarget_edit(source, HumanMotion(p, source.fps, meta=dict(source.meta)), robot, whole)
    assert "left_leg" in r.human
    assert any(j.startswith("l_") and ("hip" in j or "knee" in j or "ank" in j) for j in r.robot)


@requires_shared
def test_edit_cli_writes_both_motions_and_the_diff(tmp_path: Path, source, capsys) -> None:
    arm = [KP["left_elbow"], KP["left_wrist"]]
    p = _rotate(source.positions, arm, KP["left_shoulder"], _bump(source.num_frames, 40, 80, -0.8), axis=0)
    z2y = lambda a: np.stack([a[..., 1], a[..., 2], a[..., 0]], axis=-1)  # canonical z-up -> HumanML3D y-up
    np.save(tmp_path / "src.npy", z2y(source.positions))
    np.save(tmp_path / "edit.npy", z2y(p))
    code = main(["edit", str(tmp_path / "src.npy"), str(tmp_path / "edit.npy"), "--no-physics",
                 "--json", str(tmp_path / "diff.json"), "--html", str(tmp_path / "r.html")])
    out = capsys.readouterr().out
    assert code in (0, 1)
    assert "human edit: left_arm changed in frames" in out and "equal the source's robot motion" in out
    assert (tmp_path / "edit_source_op3.npz").is_file() and (tmp_path / "edit_edited_op3.npz").is_file()
    doc = json.loads((tmp_path / "diff.json").read_text())
    assert set(doc["human_parts_changed"]) == {"left_arm"} and "edit_report" in doc
    page = (tmp_path / "r.html").read_text()
    assert "Edit against the source" in page and "left_arm changed in frames" in page


@requires_shared
def test_a_pair_of_different_bodies_is_refused_in_one_line(capsys) -> None:
    code = main(["edit", str(MOTIONS / "humanml3d_joints" / "012314.npy"),
                 str(MOTIONS / "bvh" / "xia_neutral_01_000.bvh"), "--no-physics"])
    err = capsys.readouterr().err
    assert code == 2 and "different skeletons" in err and err.count("\n") == 1


@requires_shared
def test_batch_of_pairs_summarises_the_edits_that_stay_executable(tmp_path: Path, source, capsys) -> None:
    arm = [KP["right_elbow"], KP["right_wrist"]]
    p = _rotate(source.positions, arm, KP["right_shoulder"], _bump(source.num_frames, 40, 80, 0.8), axis=0)
    z2y = lambda a: np.stack([a[..., 1], a[..., 2], a[..., 0]], axis=-1)
    np.save(tmp_path / "src.npy", z2y(source.positions))
    np.save(tmp_path / "edit.npy", z2y(p))
    (tmp_path / "pairs.txt").write_text("# source\tedit\nsrc.npy\tedit.npy\n")
    out = tmp_path / "r.jsonl"
    code = main(["batch", "--pairs", str(tmp_path / "pairs.txt"), "--out", str(out), "--no-physics", "-j", "1", "-q",
                 "--save-motions", str(tmp_path / "motions")])
    text = capsys.readouterr().out
    assert code == 0 and "edit pairs: 1; the edit stays executable in" in text
    row = json.loads(out.read_text().splitlines()[0])
    assert row["error"] is None and row["edit"]["human_parts_changed"] == ["right_arm"]
    assert all(j.startswith("r_") for j in row["edit"]["robot_joints_changed"])
    assert Path(row["motion_file"]).is_file() and Path(row["edit"]["source_motion_file"]).is_file()


@requires_shared
def test_balance_overrides_kept_joints_only_where_the_exact_composition_loses_it(robot) -> None:
    from motion2robot.retarget import RetargetOptions
    from motion2robot.validate import CheckOptions, check

    src = read_motion(MOTIONS / "humanml3d_joints" / "M010968.npy")[0]  # standing still (BMLmovi)
    leg = [KP["right_knee"], KP["right_ankle"], KP["right_foot"]]
    p = _rotate(src.positions, leg, KP["right_hip"], _bump(src.num_frames, 15, 55, 0.9), axis=1)  # knee raised
    edit = HumanMotion(p, src.fps, meta=dict(src.meta))
    opts = RetargetOptions(tempo="human", legs="whole")
    exact = retarget_edit(src, edit, robot, opts, balance_override=False)
    over = retarget_edit(src, edit, robot, opts)
    parts = hinge_parts(robot)
    kept = np.array([h for h, ps in enumerate(parts) if "right_leg" not in ps])
    assert len(kept) == len(parts) - 6 and set(exact.human) == {"right_leg"}
    # forbidden: every kept joint and the root exactly the source's, and the need reported with its reason
    q_x, q_s = exact.edited.qpos, exact.source.qpos
    assert np.abs(q_x[:, 7 + kept] - q_s[:, 7 + kept]).max() <= 1e-6 and np.abs(q_x[:, :7] - q_s[:, :7]).max() <= 1e-6
    ox = exact.info["balance_override"]
    assert not ox["applied"] and ox["frame_list"] and ox["why"][0].startswith("balance: the ZMP leaves")
    fails = set(check(exact.edited, robot, CheckOptions(physics=False)).checks["balance"]["frames"])
    assert set(ox["frame_list"]) <= fails  # the exact composition does lose its balance there
    assert check(exact.source, robot, CheckOptions(physics=False)).checks["balance"]["ok"]  # the source does not
    # allowed: those frames overridden (widened where the blend into them fails), balance kept there,
    # kept joints exact beyond them plus the blend
    o = over.info["balance_override"]
    assert o["applied"] and set(ox["frame_list"]) <= set(o["frame_list"]) and {"l_knee", "root"} <= set(o["joints"])
    after = set(check(over.edited, robot, CheckOptions(physics=False)).checks["balance"]["frames"])
    assert not after & set(o["frame_list"])
    blend, t = over.info["blend_frames"], over.source.num_frames
    far = np.abs(np.arange(t)[:, None] - np.array(o["frame_list"])[None]).min(axis=1) > blend
    q_o = over.edited.qpos
    assert far.sum() > 10 and np.abs(q_o[far][:, 7 + kept] - q_s[far][:, 7 + kept]).max() <= 1e-6
    assert np.abs(q_o[far, :7] - q_s[far, :7]).max() <= 1e-6


@requires_shared
def test_no_override_where_the_exact_composition_keeps_its_balance(source, robot) -> None:
    arm = [KP["right_elbow"], KP["right_wrist"]]
    p = _rotate(source.positions, arm, KP["right_shoulder"], _bump(source.num_frames, 40, 80, 0.8), axis=0)
    edit = HumanMotion(p, source.fps, meta=dict(source.meta))
    allowed = retarget_edit(source, edit, robot)
    exact = retarget_edit(source, edit, robot, balance_override=False)
    assert allowed.info["balance_override"] is None and exact.info["balance_override"] is None
    assert np.array_equal(allowed.edited.qpos, exact.edited.qpos)  # nothing overridden: the exact composition


@requires_shared
def test_edit_cli_reports_the_override_in_text_json_and_html(tmp_path: Path, capsys) -> None:
    src = read_motion(MOTIONS / "humanml3d_joints" / "M010968.npy")[0]
    leg = [KP["right_knee"], KP["right_ankle"], KP["right_foot"]]
    p = _rotate(src.positions, leg, KP["right_hip"], _bump(src.num_frames, 15, 55, 0.9), axis=1)
    z2y = lambda a: np.stack([a[..., 1], a[..., 2], a[..., 0]], axis=-1)
    np.save(tmp_path / "src.npy", z2y(src.positions))
    np.save(tmp_path / "knee.npy", z2y(p))
    args = ["edit", str(tmp_path / "src.npy"), str(tmp_path / "knee.npy"), "--no-physics", "--tempo", "human",
            "--legs", "whole"]
    main(args + ["--json", str(tmp_path / "d.json"), "--html", str(tmp_path / "r.html")])
    out = capsys.readouterr().out
    assert "balance overrode the unchanged joints in frames" in out and "the ZMP leaves the support polygon" in out
    doc = json.loads((tmp_path / "d.json").read_text())
    assert doc["balance_override"]["applied"] and "l_knee" in doc["balance_override"]["joints"]
    assert "balance overrode the unchanged joints" in (tmp_path / "r.html").read_text()
    assert main(args + ["--no-balance-override"]) == 1  # forbidden: infeasible, with the reason
    out = capsys.readouterr().out
    assert "the edit is infeasible in frames" in out and "--no-balance-override forbids" in out
    assert "14 of 20 joints and the root equal the source's robot motion in every frame" in out

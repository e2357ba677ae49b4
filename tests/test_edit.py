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
    code = main(["batch", "--pairs", str(tmp_path / "pairs.txt"), "--out", str(out), "--no-physics", "-j", "1", "-q"])
    text = capsys.readouterr().out
    assert code == 0 and "edit pairs: 1; the edit stays executable in" in text
    row = json.loads(out.read_text().splitlines()[0])
    assert row["error"] is None and row["edit"]["human_parts_changed"] == ["right_arm"]
    assert all(j.startswith("r_") for j in row["edit"]["robot_joints_changed"])


@requires_shared
def test_balance_override_only_where_the_composition_loses_balance(source, robot) -> None:
    arm = [KP["right_elbow"], KP["right_wrist"]]
    p = _rotate(source.positions, arm, KP["right_shoulder"], _bump(source.num_frames, 40, 80, 0.8), axis=0)
    edit = HumanMotion(p, source.fps, meta=dict(source.meta))
    plain = retarget_edit(source, edit, robot)
    over = retarget_edit(source, edit, robot, balance_override=True)
    frames = over.info["balance_override_frames"]
    d = np.abs(over.edited.qpos - plain.edited.qpos).max(axis=1)
    if frames is None:  # nothing to override: the same motion
        assert d.max() == 0.0
    else:  # only inside the retargeted window (plus nothing outside it)
        lo, hi = over.info["retargeted_window"]
        assert d[:lo].max(initial=0) == 0.0 and d[hi:].max(initial=0) == 0.0

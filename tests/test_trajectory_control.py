"""Trajectory control: the requested root path (OmniControl hint, --trajectory) against the robot's."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2robot.batch.summary import format_summary, summarize
from motion2robot.cli import main
from motion2robot.motion import read_motion
from motion2robot.retarget.control_path import with_control_path
from tests._shared import MOTIONS, requires_shared

CLIP = "012314"


def _raw() -> np.ndarray:
    return np.load(MOTIONS / "humanml3d_joints" / f"{CLIP}.npy").astype(np.float64)


def _results_with_hint(path: Path, raw: np.ndarray, controlled: slice) -> Path:
    t = len(raw)
    hint = np.zeros((1, t + 10, 22, 3))
    hint[0, controlled, 0] = raw[controlled, 0]  # the pelvis, in the motion's own space
    res = {"motion": raw.transpose(1, 2, 0)[None].astype(np.float32), "text": ["walk along the path"],
           "lengths": np.array([t]), "num_samples": 1, "num_repetitions": 1, "hint": hint}
    np.save(path, np.array(res, dtype=object), allow_pickle=True)
    return path


@requires_shared
def test_omnicontrol_hint_becomes_the_canonical_control_path(tmp_path: Path) -> None:
    raw = _raw()
    m = read_motion(_results_with_hint(tmp_path / "results.npy", raw, slice(20, 120)), clip=0)[0]
    path = m.meta["control_path"]
    assert m.meta["control_source"] == "hint (pelvis)" and len(path) == m.num_frames
    assert all(p is None for p in path[:20] + path[120:]) and all(p is not None for p in path[20:120])
    got = np.array(path[20:120], dtype=float)
    np.testing.assert_allclose(got, m.positions[20:120, 0], atol=1e-5)  # float32 file


@requires_shared
def test_robot_error_against_the_requested_path(tmp_path: Path) -> None:
    from motion2robot.retarget import RetargetOptions, retarget
    from motion2robot.robot import load_robot
    from motion2robot.validate import CheckOptions, check

    raw = _raw()
    np.save(tmp_path / "m.npy", raw)
    np.save(tmp_path / "path.npy", raw[:, 0, [0, 2]])  # (T, 2): the ground axes x, z of a y-up file
    robot = load_robot("op3")
    human = read_motion(tmp_path / "m.npy", trajectory=tmp_path / "path.npy")[0]
    whole = RetargetOptions(tempo="human", legs="whole")  # the robot walks the human's path
    motion = with_control_path(retarget(human, robot, whole), human)
    c = check(motion, robot, CheckOptions(physics=False)).checks["trajectory"]
    assert c["control_frames"] == motion.num_frames == human.num_frames  # every frame controlled
    assert c["control_mean_error_m"] == pytest.approx(c["mean_error_m"], abs=2e-4)  # the path is the pelvis's
    legs = motion.meta["scale"]["legs"]
    assert c["control_mean_error_human_m"] == pytest.approx(c["control_mean_error_m"] / legs, abs=2e-4)
    np.save(tmp_path / "off.npy", raw[:, 0, [0, 2]] + [0.5, 0.0])  # asked to walk 0.5 m to the side
    human2 = read_motion(tmp_path / "m.npy", trajectory=tmp_path / "off.npy")[0]
    c2 = check(with_control_path(retarget(human2, robot, whole), human2), robot,
               CheckOptions(physics=False)).checks["trajectory"]
    assert 0.45 < c2["control_mean_error_human_m"] < 0.55


def test_batch_summary_reports_requested_trajectories() -> None:
    rows = [{"key": "a#0", "feasible": True, "control": {"control_mean_error_m": 0.02, "control_max_error_m": 0.05,
                                                            "control_mean_error_human_m": 0.07}},
            {"key": "b#0", "feasible": True}]
    s = summarize(rows)
    assert s.control == {"clips": 1, "mean_error_m": 0.02, "mean_error_human_m": 0.07, "max_error_m": 0.05}
    assert "requested trajectories (1 clips): root error mean 2.0 cm on the robot (7.0 cm at human scale)" in format_summary(s)


@requires_shared
@pytest.mark.parametrize("shape", [(199, 4), (10, 2), (199,)])
def test_a_trajectory_of_the_wrong_shape_is_one_line_exit_2(tmp_path: Path, capsys, shape) -> None:
    np.save(tmp_path / "t.npy", np.zeros(shape))
    assert main(["inspect", str(MOTIONS / "humanml3d_joints" / "007005.npy"), "--trajectory", str(tmp_path / "t.npy")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "root path" in err and str(tmp_path / "t.npy") in err


@requires_shared
def test_a_slowed_tempo_stretches_the_requested_path(tmp_path: Path) -> None:
    from motion2robot.retarget import RetargetOptions, retarget
    from motion2robot.robot import load_robot

    raw = _raw()
    np.save(tmp_path / "m.npy", raw)
    np.save(tmp_path / "path.npy", raw[:, 0, [0, 2]])
    human = read_motion(tmp_path / "m.npy", trajectory=tmp_path / "path.npy")[0]
    motion = with_control_path(retarget(human, load_robot("op3"), RetargetOptions(tempo=2.0, legs="whole")), human)
    xy = np.array(motion.meta["control_xy"], dtype=float)
    assert len(xy) == motion.num_frames > human.num_frames
    legs = motion.meta["scale"]["legs"]
    np.testing.assert_allclose(xy[0], np.array(human.meta["control_path"][0][:2]) * legs, atol=1e-12)
    np.testing.assert_allclose(xy[-1], np.array(human.meta["control_path"][-1][:2]) * legs, atol=1e-12)


def test_the_path_follows_the_output_rate_by_time() -> None:
    from motion2robot.retarget.control_path import on_robot_frames

    path = [[0.1 * i, -0.05 * i, None] for i in range(170)]  # 20 fps: x = 2 m/s * t, y = -1 m/s * t
    path[50] = None  # one uncontrolled human frame
    frames = on_robot_frames(path, 254, 30.0, 20.0)  # retarget --fps 30: floor(169 * 1.5) + 1 frames
    assert len(frames) == 254
    t = np.arange(254) / 30.0
    near = np.abs(t * 20.0 - 50) < 1.0  # robot frames interpolated from human frame 50
    assert all(frames[r] is None for r in np.flatnonzero(near))
    got = np.array([f for r, f in enumerate(frames) if not near[r]])
    np.testing.assert_allclose(got, np.stack([2.0 * t, -1.0 * t], axis=1)[~near], atol=1e-12)
    slow = on_robot_frames(path, 253 * 2 + 1, 30.0, 20.0, tempo=2.0)  # and slowed x2 on top
    np.testing.assert_allclose(slow[2 * 30], [2.0, -1.0], atol=1e-12)  # robot 2 s = human 1 s


@requires_shared
def test_retarget_at_another_rate_keeps_the_requested_path(tmp_path: Path, capsys) -> None:
    from motion2robot.robot_motion import RobotMotion

    raw = _raw()
    np.save(tmp_path / "m.npy", raw)
    np.save(tmp_path / "path.npy", raw[:, 0, [0, 2]])  # the pelvis's own ground path
    out = tmp_path / "r30.npz"
    assert main(["retarget", str(tmp_path / "m.npy"), "--trajectory", str(tmp_path / "path.npy"), "--fps", "30",
                 "--tempo", "human", "--legs", "whole", "-o", str(out)]) == 0
    motion = RobotMotion.load(out)
    assert motion.fps == 30.0 and motion.num_frames == int(169 * 1.5) + 1
    xy = np.array(motion.meta["control_xy"], dtype=float)
    assert xy.shape == (motion.num_frames, 2)  # every output frame controlled
    human = read_motion(tmp_path / "m.npy", trajectory=tmp_path / "path.npy")[0]
    path = np.array([p[:2] for p in human.meta["control_path"]], dtype=float)
    u = np.arange(motion.num_frames) / 30.0 * 20.0  # by time, not by frame count
    expected = np.stack([np.interp(u, np.arange(len(path)), path[:, k]) for k in (0, 1)], axis=1)
    np.testing.assert_allclose(xy, expected * motion.meta["scale"]["legs"], atol=1e-9)
    from motion2robot.robot import load_robot
    from motion2robot.validate import CheckOptions, check

    c = check(motion, load_robot("op3"), CheckOptions(physics=False)).checks["trajectory"]
    assert c["control_frames"] == motion.num_frames
    assert c["control_mean_error_m"] == pytest.approx(c["mean_error_m"], abs=1e-3)  # the path is the pelvis's
    capsys.readouterr()
    assert main(["check", str(out), "--no-physics"]) in (0, 1)
    text = capsys.readouterr().out
    assert "requested trajectory (--trajectory path.npy)" in text

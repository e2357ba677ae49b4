"""Fidelity figures and the per-set figures of the score table."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.batch.summary import summarize
from motion2robot.score.fidelity import (
    centred,
    contact_agreement,
    keypoint_error,
    robot_contacts,
    tempo_index,
)
from motion2robot.score.figures import set_figures
from tests._shared import MOTIONS, requires_shared


def test_tempo_index_maps_robot_frames_to_human_frames() -> None:
    assert tempo_index(5, 5, 1.0).tolist() == [0, 1, 2, 3, 4]
    assert tempo_index(9, 5, 2.0).tolist() == [0, 0, 1, 2, 2, 2, 3, 4, 4]  # round half to even
    assert tempo_index(12, 5, 2.0).max() == 4


def test_contacts_agreement_and_keypoint_error() -> None:
    T = 6
    corners = np.zeros((T, 2, 4, 3))
    corners[:, 1, :, 2] = 0.05            # right foot 5 cm up: never in contact
    corners[3:, 0, :, 0] = np.arange(3)[:, None] * 0.1  # left foot slides 0.1 m per frame from frame 3
    c = robot_contacts(corners, fps=10.0, height=0.01, speed=0.3)
    assert c[:, 1].tolist() == [False] * T
    assert c[:, 0].tolist() == [True, True, True, False, False, False]  # 1 m/s sliding is not contact
    human = np.array([[True, False]] * T)
    assert contact_agreement(c, human) == pytest.approx(9 / 12)
    a = np.zeros((4, 3, 3))
    b = a.copy()
    b[..., 2] = 0.02
    assert keypoint_error(a, b) == pytest.approx(0.02)
    names = ("pelvis", "left_hip", "right_hip")
    assert keypoint_error(centred(a, names), centred(b, names)) == 0.0  # a shifted skeleton: same pose
    b[:, 1, 0] = 0.03
    assert keypoint_error(centred(a, names), centred(b, names)) == pytest.approx(0.01)


def _row(key: str, feasible: bool | None, tempo: float = 1.0, fallback: bool = False, error: str | None = None,
         kp: float = 0.05, agree: float = 0.9, failed: tuple = ()) -> dict:
    return {"key": key, "path": key, "clip": 0, "frames": 10, "feasible": feasible, "error": error,
            "failed_checks": list(failed), "reasons": [f"{c} fails in frames 1-3" for c in failed],
            "figures": {} if error else {"tempo": tempo, "fallback": {"mode": "stance"} if fallback else None},
            "fidelity": None if error else {"keypoint_error_m": kp, "keypoint_error_human_m": kp * 3,
                                            "keypoint_error_pose_m": kp / 2,
                                            "contact_agreement": agree},
            "timings": {"total_s": 2.0, "cpu_s": None if error else 1.5}}


def test_set_figures_from_rows() -> None:
    rows = [_row("a", True), _row("b", True, tempo=2.0, fallback=True, kp=0.15, agree=0.7),
            _row("c", True, tempo=1.5), _row("d", False, tempo=2.5, failed=("rollout", "balance")),
            _row("e", None, error="read: broken")]
    f = set_figures("gen", rows)
    s = summarize(rows)
    assert (f.samples, f.executable, f.not_executable, f.errors) == (5, 3, 1, 1) == (s.clips, s.feasible, s.infeasible, s.errors)
    assert f.executable_share == pytest.approx(s.executable_rate)
    assert (f.tempo_median, f.tempo_p90) == (1.5, pytest.approx(1.9))  # over the executable samples only
    assert f.slowed_share == pytest.approx(2 / 5) and f.fallback_share == pytest.approx(1 / 5)
    assert f.keypoint_error_cm == pytest.approx(100 * (0.05 * 3 + 0.15) / 4) and f.fidelity_samples == 4
    assert f.keypoint_error_pose_cm == pytest.approx(f.keypoint_error_cm / 2)
    assert f.contact_agreement == pytest.approx((0.9 * 3 + 0.7) / 4)
    assert f.top_checks == (("balance", 1), ("rollout", 1)) and f.top_reason[1] == 1
    assert f.cpu_s_per_sample == 1.5 and f.samples_per_min_per_core == 40.0
    empty = set_figures("none", [])
    assert empty.samples == 0 and empty.executable_share is None and empty.tempo_median is None


@requires_shared
def test_fidelity_of_a_real_clip_matches_the_solvers_residual() -> None:
    """On a clip retargeted whole-body at x1.0, the keypoint error is the solver's own per-frame
    residual (same targets, measured with MuJoCo instead of casadi); the robot stands as the
    person does, so the contacts agree."""
    from motion2robot.motion import read_motion
    from motion2robot.retarget import RetargetOptions, retarget
    from motion2robot.robot import load_robot
    from motion2robot.score.fidelity import fidelity

    robot = load_robot("op3")
    human = read_motion(MOTIONS / "humanml3d_joints/M010968.npy")[0]
    motion = retarget(human, robot, RetargetOptions(tempo="human", legs="whole"))
    fid = fidelity(human, motion, robot)
    solver = float(np.mean(motion.meta["solver"]["residual_per_frame"]))
    assert fid["keypoint_error_m"] == pytest.approx(solver, rel=1e-3, abs=1e-4)
    assert fid["keypoint_error_human_m"] == pytest.approx(fid["keypoint_error_m"] / motion.meta["scale"]["legs"], rel=1e-3)
    assert fid["contact_agreement"] > 0.95 and fid["contact_labels"] == "detected"
    assert 0 < fid["keypoint_error_pose_m"] < 0.1
    slow = retarget(human, robot, RetargetOptions(tempo=2.0, legs="whole"))
    fid2 = fidelity(human, slow, robot)
    assert slow.num_frames == 2 * (human.num_frames - 1) + 1
    assert fid2["keypoint_error_m"] == pytest.approx(float(np.mean(slow.meta["solver"]["residual_per_frame"])), rel=1e-3, abs=1e-4)

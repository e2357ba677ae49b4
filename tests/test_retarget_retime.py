"""Retiming (motion2robot.retarget.retime): a robot motion's poses played at another tempo, and
the recipe of a result repeated on another human motion (motion2robot.retarget.remake)."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from motion2robot.motion import read_motion
from motion2robot.projection import hinge_rms, project
from motion2robot.retarget import RetargetOptions, retarget, retarget_and_check
from motion2robot.retarget.remake import remake
from motion2robot.retarget.retime import resample_meta, retime, sample_poses
from motion2robot.retarget.tempo import stretch
from tests._demo import demo_clip, op3
from tests._shared import MOTIONS, requires_shared


_robot = op3


@functools.lru_cache(maxsize=1)
def _demo():
    """The bundled demo clip (first 80 frames) and its whole-body robot motion at x1.6."""
    human = demo_clip(80)
    return human, retarget(human, _robot(), RetargetOptions(tempo=1.6, legs="whole"))


def test_a_retimed_motion_has_the_frames_of_one_retargeted_at_that_tempo() -> None:
    human, slow = _demo()
    for k in (1.0, 1.25, 2.0):
        again = retime(slow, _robot(), k, human.num_frames)
        assert again.num_frames == stretch(human, k).num_frames
        assert again.meta["tempo"] == k and again.meta["retimed"] == {"from_tempo": 1.6}
        assert np.shape(again.meta["contacts"]) == (again.num_frames, 2)
        assert np.shape(again.meta["human_root_xy"]) == (again.num_frames, 2)
        assert len(again.meta["solver"]["residual_per_frame"]) == again.num_frames
        assert np.allclose(np.linalg.norm(again.qpos[:, 3:7], axis=1), 1.0)
        assert np.all(again.qpos[:, 7:] >= _robot().lower) and np.all(again.qpos[:, 7:] <= _robot().upper)


def test_played_faster_and_back_the_poses_come_back() -> None:
    """x1.6 -> x1.0 -> x1.6: the frames between the kept ones interpolated twice in joint space
    (the demo's squat at 20 fps, 80 frames: measured 9e-4 rad RMS, what a spline through every
    1.6th frame of a 20 fps motion misses; an AIST++ dance at 60 fps: 2e-5); x1.6 -> x1.6 is the
    motion itself."""
    human, slow = _demo()
    rb = _robot()
    same = retime(slow, rb, 1.6, human.num_frames)
    np.testing.assert_allclose(same.qpos, slow.qpos, atol=1e-12)
    back = retime(retime(slow, rb, 1.0, human.num_frames), rb, 1.6, human.num_frames)
    assert 0 < hinge_rms(back, slow) < 2e-3
    assert np.abs(back.root_pos - slow.root_pos).max() < 1e-3


def test_poses_at_whole_frames_are_the_poses_given_and_between_them_a_spline() -> None:
    _, slow = _demo()
    rb = _robot()
    q = np.asarray(slow.qpos)
    np.testing.assert_allclose(sample_poses(q, np.arange(5.0), rb.lower, rb.upper), q[:5], atol=1e-12)
    mid = sample_poses(q, np.array([10.5]), rb.lower, rb.upper)[0]
    assert np.all(np.minimum(q[10, 7:], q[11, 7:]) - 1e-3 <= mid[7:]) and np.all(mid[7:] <= np.maximum(q[10, 7:], q[11, 7:]) + 1e-3)
    flipped = q.copy()
    flipped[1::2, 3:7] *= -1  # the same rotations, every other one written with the opposite sign
    np.testing.assert_allclose(np.abs(sample_poses(flipped, np.array([10.5]), rb.lower, rb.upper)[0, 3:7]),
                               np.abs(mid[3:7]), atol=1e-12)


def test_per_frame_meta_is_resampled_and_the_rest_kept() -> None:
    meta = {"contacts": [[1, 0], [1, 1], [0, 1]], "human_root_xy": [[0.0, 0.0], [1.0, 2.0], [2.0, 4.0]],
            "solver": {"residual_per_frame": [0.0, 1.0, 2.0], "max_residual": 2.0}, "attempts": [1, 2, 3],
            "scale": {"legs": 0.5}}
    out = resample_meta(meta, np.array([0.0, 0.5, 1.4, 2.0]), 3)
    assert out["contacts"] == [[1, 0], [1, 0], [1, 1], [0, 1]]  # labels at the nearest frame
    assert out["human_root_xy"] == [[0.0, 0.0], [0.5, 1.0], [1.4, 2.8], [2.0, 4.0]]
    assert out["solver"] == {"residual_per_frame": [0.0, 0.5, 1.4, 2.0], "max_residual": 2.0}
    assert out["attempts"] == [1, 2, 3] and out["scale"] == {"legs": 0.5}


def test_remake_repeats_a_fixed_tempo_and_legs() -> None:
    human, slow = _demo()
    assert hinge_rms(remake(human, _robot(), slow.with_(meta={"tempo": 1.6})), slow) == pytest.approx(0.0, abs=1e-12)


@requires_shared
def test_a_dance_slowed_x1_6_projects_exactly_and_comes_back() -> None:
    """The AIST++ break-dance walks its steps at x1.6 (slower fails torque, faster poses too): its
    projection is the robot's poses at the human's frames, which the default retargeting plays at
    x1.6 again (the exact poses fail at x1.0 and x1.25): idempotent within 1e-4 rad, where target
    correction rounds stalled at 0.0022 rad; ``remake`` of the clip is its robot motion."""
    rb = _robot()
    human = read_motion(MOTIONS / "smpl" / "aistpp_gBR_sBM_cAll_d04_mBR0_ch01.pkl")[0]
    p = project(human, rb)
    meta = p.robot_motion.meta
    assert meta["tempo"] == 1.6 and meta["fallback"]["mode"] == "steps" and p.executable
    assert [a.get("retime_of") for a in meta["attempts"]][-2:] == [1.6, 1.6]  # its poses tried faster, failing
    assert p.reached and p.idempotence_rms < 1e-4
    again, report = retarget_and_check(p.human, rb)
    assert report.feasible and again.meta["tempo"] == 1.6 and hinge_rms(again, p.robot_motion) < 1e-4
    assert "played x1.60 slower" in again.meta["tempo_reason"]
    assert hinge_rms(remake(human, rb, p.robot_motion), p.robot_motion) < 1e-9


@requires_shared
def test_a_dance_failing_at_every_tempo_passes_replayed_from_its_nearest_attempt() -> None:
    """Bandai's dance fails the physics playback in its stance at x1.0 and x2.5 (nothing else
    passes more); the x2.5 stance's own keypoints, re-solved at x1.0, pass every check."""
    rb = _robot()
    human = read_motion(MOTIONS / "bvh" / "bandai_dance-short_normal_001.bvh")[0]
    motion, report = retarget_and_check(human, rb)
    assert report.feasible and motion.meta["tempo"] == 1.0 and motion.meta["replayed"] == {"from_tempo": 2.5}
    assert "the nearest to passing, failing rollout" in motion.meta["tempo_reason"]
    assert not any(a["feasible"] for a in motion.meta["attempts"][:-1])

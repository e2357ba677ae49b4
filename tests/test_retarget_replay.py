"""The tempo policy's replays (motion2robot.retarget.replay): a slowed pass re-solved at the
generated tempo, else its poses played faster; the nearest attempt to passing re-solved; a
robot-shaped motion's exact poses played slower."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.motion import HumanMotion, read_motion
from motion2robot.projection import hinge_rms, project
from motion2robot.retarget import RetargetOptions, retarget_and_check
from motion2robot.robot import load_robot
from tests._shared import MOTIONS, requires_shared


class _Report:
    def __init__(self, failed: tuple[str, ...]):
        self.feasible, self.figures = not failed, {}
        self.checks = {name: {"ok": False} for name in failed}


class _Motion:
    def __init__(self, legs: str, k: float, replayed: bool = False, retimed_from: float | None = None):
        self.legs, self.k, self.replayed, self.retimed_from, self.meta = legs, k, replayed, retimed_from, {}

    def with_(self, meta):
        self.meta = {**self.meta, **meta}
        return self


def _plan(monkeypatch, fails, cap: float = 1.25, reached: _Motion | None = None):
    """plan() with stand-ins: ``fails(motion)`` the checks a stand-in motion fails (legs, tempo k,
    replayed, retimed_from); the replay marks the human it gives back, a retime the motion it
    plays. Returns the chosen motion and every motion judged, in order."""
    import motion2robot.retarget.executable as ex
    import motion2robot.retarget.replay as rp

    T = 30
    pos = np.zeros((T, 22, 3))
    pos[:, :, 2] = 0.9
    human = HumanMotion(pos, 20.0, contacts=np.ones((T, 2), bool))
    judged = []

    def solve(h, legs):
        return _Motion(legs, float(h.meta.get("tempo", 1.0)), bool(h.meta.get("replay")))

    def judge(m):
        judged.append(m)
        return _Report(tuple(fails(m)))

    monkeypatch.setattr(ex, "short_shifts", lambda *a: None)
    monkeypatch.setattr(ex, "_judge", lambda robot, options, full=False: judge)
    monkeypatch.setattr(rp, "retime", lambda m, robot, k, n: _Motion(m.legs, k, False, m.meta.get("tempo", 1.0)))
    def replay(m):
        assert m.meta["tempo"] == m.k  # mapped back at the tempo it was made at (the human's frame i is its i * k)
        return human.with_(meta={"replay": True})

    motion, _ = ex.plan(human, None, "auto", "auto", cap, solve, reached=reached, replay=replay)
    return motion, judged


def _slow(m) -> tuple[str, ...]:
    """Passes only slowed (solved at a slower tempo)."""
    return () if m.k > 1 and m.retimed_from is None else ("acceleration",)


def test_a_slowed_pass_that_passes_replayed_is_kept_at_the_generated_tempo(monkeypatch):
    motion, judged = _plan(monkeypatch, lambda m: () if m.replayed else _slow(m))
    assert judged[-1].replayed and motion.replayed
    assert motion.meta["tempo"] == 1.0 and motion.meta["replayed"] == {"from_tempo": 1.25}
    assert motion.meta["attempts"][-1] == {"legs": "whole", "tempo": 1.0, "feasible": True, "failed": [],
                                           "replay_of": 1.25}
    assert "(the smallest slow-down that passes), replayed at the generated tempo" in motion.meta["tempo_reason"]


def test_a_replay_that_fails_leaves_the_slowed_pass_once_its_poses_fail_faster(monkeypatch):
    motion, judged = _plan(monkeypatch, _slow)
    assert [(m.k, m.replayed, m.retimed_from) for m in judged[-2:]] == [(1.0, True, None), (1.0, False, 1.25)]
    assert motion.k > 1 and not motion.replayed and motion.retimed_from is None and motion.meta["tempo"] == 1.25
    assert "replayed" not in motion.meta and "retimed" not in motion.meta
    assert motion.meta["attempts"][-2]["replay_of"] == 1.25 and motion.meta["attempts"][-1]["retime_of"] == 1.25
    assert motion.meta["attempts"][-1]["failed"] == ["acceleration"]


def test_a_slowed_pass_whose_poses_pass_faster_is_played_faster(monkeypatch):
    """Slowed x2.5 passes, x1.6 solved fails; its poses at x1.6 pass (not at 1.0 or 1.25): kept there."""
    def fails(m):
        if m.retimed_from is not None:
            return () if m.k >= 1.6 else ("torque_limits",)
        return () if m.k >= 2.5 else ("torque_limits",)

    motion, judged = _plan(monkeypatch, fails, cap=2.5)
    assert motion.retimed_from == 2.5 and motion.k == 1.6
    assert [m.k for m in judged if m.retimed_from] == [1.0, 1.25, 1.6]  # the fastest first
    assert motion.meta["tempo"] == 1.6 and motion.meta["retimed"] == {"from_tempo": 2.5}
    assert motion.meta["tempo_reason"].startswith("slowed x1.60: the robot's motion slowed x2.50")


def test_nothing_passes_but_the_nearest_slowed_attempt_replayed(monkeypatch):
    motion, judged = _plan(monkeypatch, lambda m: () if m.replayed else ("rollout",))
    assert motion.replayed and motion.meta["tempo"] == 1.0 and motion.meta["executable"] is True
    assert "(the nearest to passing, failing rollout), replayed" in motion.meta["tempo_reason"]
    assert not any(m.retimed_from for m in judged)  # a failing attempt's poses are not played faster


def test_a_robot_shaped_motion_failing_at_x1_is_played_slower_before_anything_is_solved(monkeypatch):
    exact = _Motion("whole", 1.0)
    motion, judged = _plan(monkeypatch, lambda m: () if m.retimed_from == 1.0 and m.k >= 1.25 else ("acceleration",),
                           cap=2.5, reached=exact)
    assert judged[0] is exact and [m.k for m in judged[1:]] == [1.25]  # nothing solved
    assert motion.retimed_from == 1.0 and motion.meta["tempo"] == 1.25 and motion.meta["retimed"] == {"from_tempo": 1.0}
    assert "the exact poses of this robot-shaped motion, played x1.25 slower" in motion.meta["tempo_reason"]


def test_a_robot_shaped_motion_failing_a_tempo_proof_check_is_not_played_slower(monkeypatch):
    exact = _Motion("whole", 1.0)
    motion, judged = _plan(monkeypatch, lambda m: ("joint_limits",) if m is exact else _slow(m), reached=exact)
    assert not any(m.retimed_from == 1.0 for m in judged)
    assert motion.k == 1.25 and motion.retimed_from is None  # solved slowed, as any other motion


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


@requires_shared
def test_a_slow_walk_played_faster_keeps_its_tempo_and_projects_exactly(op3):
    """Xia's neutral walk needs x1.25 as retargeted from the capture; its slowed steps re-solved at
    x1.0 fail, but their poses played at x1.0 pass every check (physics included), so the clip
    keeps its tempo, and its projection is the robot's own motion, retargeted back to it exactly."""
    human = read_motion(MOTIONS / "bvh" / "xia_neutral_01_000.bvh")[0]
    motion, report = retarget_and_check(human, op3)
    assert motion.meta["tempo"] == 1.0 and motion.meta["retimed"] == {"from_tempo": 1.25}
    assert [a.get("replay_of") for a in motion.meta["attempts"]][-2] == 1.25  # the re-solve, tried first
    assert report.feasible and motion.num_frames == human.num_frames
    assert "played at x1.00, its poses unchanged, passes" in motion.meta["tempo_reason"]
    kept, _ = retarget_and_check(human, op3, RetargetOptions(replay=False))
    assert kept.meta["tempo"] == 1.25 and "replayed" not in kept.meta and "retimed" not in kept.meta
    p = project(human, op3)
    assert p.reached and p.executable
    again, again_report = retarget_and_check(p.human, op3)
    assert again_report.feasible and hinge_rms(motion, again) < 1e-6


@requires_shared
def test_a_dance_replayed_moves_as_the_slowed_pass_did(op3):
    """The CMU dance passes at x1.25; its keypoints mapped back at that tempo (human frame i = robot
    frame 1.25 i) and re-solved at x1.0 pass: the replay travels as the slow pass does and is as
    near to the human (keypoint error, robot scale: measured 152.0 / 150.7 mm, the posture 85.8 /
    84.0 mm). Mapped back at x1.0 instead, a replay was the first 80 % of the slow pass: a Xia
    walk's stood still (its joints within 0.012 rad) and passed."""
    from motion2robot.retarget.nearness import keypoint_error
    from motion2robot.retarget.tempo import stretch

    human = read_motion(MOTIONS / "bvh" / "cmu_cc_005_02_dance.bvh")[0]
    motion, report = retarget_and_check(human, op3)
    slowed, _ = retarget_and_check(human, op3, RetargetOptions(replay=False))
    assert report.feasible and motion.meta["replayed"] == {"from_tempo": 1.25} and slowed.meta["tempo"] == 1.25
    travel = np.linalg.norm(motion.qpos[-1, :2] - motion.qpos[0, :2])
    assert travel > 0.05 and travel == pytest.approx(np.linalg.norm(slowed.qpos[-1, :2] - slowed.qpos[0, :2]), abs=0.01)
    for pose in (False, True):
        near = keypoint_error(motion, human, op3, pose=pose)
        assert near < keypoint_error(slowed, stretch(human, 1.25), op3, pose=pose) + 0.005

"""The legs policy's replay: a slowed pass replayed at the generated tempo and kept there when
that passes (motion2robot.retarget.executable)."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.motion import HumanMotion, read_motion
from motion2robot.projection import hinge_rms, project
from motion2robot.retarget import RetargetOptions, retarget_and_check
from motion2robot.robot import load_robot
from tests._shared import MOTIONS, requires_shared


class _Report:
    def __init__(self, ok: bool):
        self.feasible, self.figures = ok, {}
        self.checks = {} if ok else {"acceleration": {"ok": False}}


class _Motion:
    def __init__(self, legs: str, k: float, replayed: bool):
        self.legs, self.k, self.replayed, self.meta = legs, k, replayed, {}

    def with_(self, meta):
        self.meta = {**self.meta, **meta}
        return self


def _plan(monkeypatch, replay_passes: bool):
    """plan() with stand-ins: the whole body passes only slowed, or as a replay when
    ``replay_passes``; the replay marks the human it gives back."""
    import motion2robot.retarget.executable as ex

    T = 30
    pos = np.zeros((T, 22, 3))
    pos[:, :, 2] = 0.9
    human = HumanMotion(pos, 20.0, contacts=np.ones((T, 2), bool))
    made = []

    def solve(h, legs):
        made.append((legs, round(h.num_frames / T, 2), bool(h.meta.get("replay"))))
        return _Motion(*made[-1])

    def judge(m):
        return _Report(m.k > 1 or (m.replayed and replay_passes))

    monkeypatch.setattr(ex, "short_shifts", lambda *a: None)
    monkeypatch.setattr(ex, "_judge", lambda robot, options, full=False: judge)
    replay = lambda m: human.with_(meta={"replay": True})  # noqa: E731
    motion, _ = ex.plan(human, None, "auto", "auto", 1.25, solve, replay=replay)
    return motion, made


def test_a_slowed_pass_that_passes_replayed_is_kept_at_the_generated_tempo(monkeypatch):
    motion, made = _plan(monkeypatch, replay_passes=True)
    assert made[-1] == ("whole", 1.0, True) and motion.replayed
    assert motion.meta["tempo"] == 1.0 and motion.meta["replayed"] == {"from_tempo": 1.25}
    assert motion.meta["attempts"][-1] == {"legs": "whole", "tempo": 1.0, "feasible": True, "failed": [],
                                           "replay_of": 1.25}
    assert "replayed at the generated tempo" in motion.meta["tempo_reason"]


def test_a_replay_that_fails_leaves_the_slowed_pass(monkeypatch):
    motion, made = _plan(monkeypatch, replay_passes=False)
    assert made[-1] == ("whole", 1.0, True)  # tried, judged, not kept
    assert motion.k > 1 and not motion.replayed and motion.meta["tempo"] == 1.25
    assert "replayed" not in motion.meta and motion.meta["attempts"][-1]["replay_of"] == 1.25
    assert motion.meta["attempts"][-1]["failed"] == ["acceleration"]


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


@requires_shared
def test_a_slow_walk_replayed_keeps_its_tempo_and_projects_exactly(op3):
    """Xia's neutral walk needs x1.25 as retargeted from the capture; its slowed steps replayed
    at x1.0 pass every check (physics included), so the clip keeps its tempo, and its projection
    is the robot's own motion, retargeted back to it exactly."""
    human = read_motion(MOTIONS / "bvh" / "xia_neutral_01_000.bvh")[0]
    motion, report = retarget_and_check(human, op3)
    assert motion.meta["tempo"] == 1.0 and motion.meta["replayed"] == {"from_tempo": 1.25}
    assert report.feasible and motion.num_frames == human.num_frames
    kept, _ = retarget_and_check(human, op3, RetargetOptions(replay=False))
    assert kept.meta["tempo"] == 1.25 and "replayed" not in kept.meta
    p = project(human, op3)
    assert p.reached and p.executable
    again, again_report = retarget_and_check(p.human, op3)
    assert again_report.feasible and hinge_rms(motion, again) < 1e-6

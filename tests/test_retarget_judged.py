"""The policy's judge runs no check twice: the report of a returned attempt that already played
back is the full one; an attempt whose playback was skipped gets the full check."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import motion2robot.validate as validate
from motion2robot.motion.human import HumanMotion
from motion2robot.retarget.executable import plan
from motion2robot.retarget.judged import needs_full_check
from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate import CheckOptions


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def _human(T=30, fps=20.0):
    rng = np.random.default_rng(0)
    pos = rng.normal(0.0, 0.1, size=(T, 22, 3)) + np.array([0.0, 0.0, 0.9])
    return HumanMotion(pos, fps, contacts=np.ones((T, 2), bool), meta={"source": "constructed"})


def _report(motion, kinematic_ok: bool, played: bool, rollout_ok: bool = False):
    checks = {"joint_limits": {"ok": True, "frames": []}, "acceleration": {"ok": kinematic_ok, "frames": []},
              "rollout": ({"ok": rollout_ok, "frames": [], "fell": not rollout_ok} if played
                          else {"ok": True, "skipped": "a kinematic check already fails", "frames": []}),
              "trajectory": {"ok": True}}
    return SimpleNamespace(feasible=kinematic_ok and played and rollout_ok, checks=checks, figures={},
                           frames=motion.num_frames)


def _fake_check(monkeypatch, kinematic_ok: bool):
    """check() that fails every attempt: kinematically (playback skipped unless a full check is
    asked for) or, with ``kinematic_ok``, in the playback; records each call's kind."""
    calls = []

    def check(motion, robot, options=None, *, physics_if_feasible=False):
        calls.append("judge" if physics_if_feasible else "full")
        played = kinematic_ok or not physics_if_feasible
        return _report(motion, kinematic_ok, played=played and (options is None or options.physics))

    monkeypatch.setattr(validate, "check", check)
    return calls


def _solve(op3):
    return lambda h, legs: RobotMotion(np.tile(op3.model.qpos0, (h.num_frames, 1)), h.fps, op3.joint_names, op3.name)


def test_a_returned_attempt_that_played_back_is_not_checked_again(monkeypatch, op3):
    calls = _fake_check(monkeypatch, kinematic_ok=True)  # every attempt plays back and falls
    motion, report = plan(_human(), op3, "auto", "whole", 2.5, _solve(op3))
    assert motion.meta["executable"] is False
    assert calls == ["judge", "judge"]  # x1.0, then the cap; no second check of the cap
    assert "skipped" not in report.checks["rollout"] and report.checks["rollout"]["fell"]


def test_a_returned_attempt_without_its_playback_gets_the_full_check(monkeypatch, op3):
    calls = _fake_check(monkeypatch, kinematic_ok=False)  # the judge skips every playback
    motion, report = plan(_human(), op3, "auto", "whole", 2.5, _solve(op3))
    assert motion.meta["executable"] is False
    assert calls == ["judge", "judge", "full"]
    assert "skipped" not in report.checks["rollout"]  # the report holds the playback


def test_needs_full_check():
    m = SimpleNamespace(num_frames=10)
    skipped, played = _report(m, False, played=False), _report(m, True, played=True)
    assert needs_full_check(skipped, None) and needs_full_check(skipped, CheckOptions())
    assert not needs_full_check(played, None)
    assert not needs_full_check(skipped, CheckOptions(physics=False))  # a full check would skip it too
    assert not needs_full_check(_report(SimpleNamespace(num_frames=1), False, played=False), None)


def test_when_nothing_passes_the_attempt_failing_fewest_checks_is_returned(monkeypatch, op3):
    """A steps attempt failing five checks after a stance failing only the playback: the stance is
    returned (it used to be whichever came last)."""
    def check(motion, robot, options=None, *, physics_if_feasible=False):
        many = motion.meta.get("legs") == "steps"
        checks = {n: {"ok": not many, "frames": []} for n in ("velocity_limits", "torque_limits", "ground", "balance")}
        checks["rollout"] = {"ok": False, "frames": [], "fell": True}
        return SimpleNamespace(feasible=False, checks=checks, figures={}, frames=motion.num_frames)

    monkeypatch.setattr(validate, "check", check)

    def solve(h, legs):
        m = RobotMotion(np.tile(op3.model.qpos0, (h.num_frames, 1)), h.fps, op3.joint_names, op3.name)
        return m.with_(meta={"legs": legs})

    monkeypatch.setattr("motion2robot.retarget.executable.auto_legs", lambda *a: ["stance", "steps"])
    motion, report = plan(_human(), op3, "human", "auto", 2.5, solve)
    assert [a["legs"] for a in motion.meta["attempts"]] == ["stance", "steps"]
    assert motion.meta["fallback"]["mode"] == "stance" and motion.meta["executable"] is False

"""One attempt of the tempo and legs policy (:mod:`~.executable`): a robot motion, how it was made
and its ``check`` report."""

from __future__ import annotations

from dataclasses import dataclass

from motion2robot.robot_motion import RobotMotion

#: Checks a slower tempo cannot make pass (the same postures, only slower): an attempt failing any
#: of them is not tried slower.
TEMPO_PROOF = frozenset({"joint_limits", "self_collision", "ground"})


@dataclass(frozen=True)
class Attempt:
    """legs: the legs mode; factor: the tempo factor (1.0 = as generated); report: the
    FeasibilityReport, or None when not judged; replay_of: the slowed tempo this x1.0 attempt
    re-solves (:func:`~.replay.replayed`); retime_of: the tempo of the motion this attempt plays
    at ``factor`` (:mod:`~.retime`: its poses, nothing solved again)."""

    legs: str
    factor: float
    motion: RobotMotion
    report: object | None
    replay_of: float | None = None
    retime_of: float | None = None

    @property
    def feasible(self) -> bool:
        return bool(self.report is not None and self.report.feasible)

    def failed(self) -> list[str]:
        if self.report is None:
            return []
        return [n for n, c in self.report.checks.items() if c.get("ok") is False]

    def record(self) -> dict:
        """This attempt as ``meta["attempts"]`` lists it."""
        return {"legs": self.legs, "tempo": self.factor, "feasible": self.feasible if self.report else None,
                "failed": self.failed(), **({"replay_of": self.replay_of} if self.replay_of else {}),
                **({"retime_of": self.retime_of} if self.retime_of is not None else {})}


def tempo_proof(motion: RobotMotion) -> frozenset:
    """The checks a slower tempo cannot make ``motion`` pass: :data:`TEMPO_PROOF`, without
    ``ground`` when its foot plan left swings free for being too fast at this tempo (slower, they
    are planned: lifted, the stance foot held)."""
    feet = (motion.meta.get("solver") or {}).get("feet") or {}
    return TEMPO_PROOF - {"ground"} if feet.get("free_swings_too_fast") else TEMPO_PROOF

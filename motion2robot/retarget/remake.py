"""The robot motion of a human motion made the way another result was made, nothing judged.

``retarget`` chooses a tempo, legs and, for a slowed pass, a replay (:mod:`~.replay`); its meta
says which. :func:`remake` repeats that recipe on another human motion (the same clip moved by
noise, resampled to another rate, ...) so a comparison measures the retargeting rather than the
policy's choice: ``meta["replayed"]`` (slowed at its ``from_tempo``, mapped back, re-solved at
x1.0), ``meta["retimed"]`` (solved at its ``from_tempo``, or the exact poses for a robot-shaped
motion at x1.0, played at the tempo chosen), ``meta["reached"]`` (the exact poses), else the
legs mode at the tempo chosen.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

from motion2robot.motion.human import HumanMotion
from motion2robot.motion.ops import resample
from motion2robot.retarget.exact import exact_motion
from motion2robot.retarget.executable import legs_of
from motion2robot.retarget.options import RetargetOptions
from motion2robot.retarget.retime import retime
from motion2robot.retarget.tempo import stretch
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion


def _from(meta: Mapping, key: str) -> float | None:
    made = meta.get(key)
    return float(made["from_tempo"]) if isinstance(made, Mapping) and "from_tempo" in made else None


def remake(human: HumanMotion, robot: Robot, motion: RobotMotion, options: RetargetOptions | None = None) -> RobotMotion:
    """The robot motion of ``human`` (canonical) made as ``motion`` was (see the module text), at
    ``options.fps`` when given (``human`` resampled first, as ``retarget`` does)."""
    from motion2robot.projection.mapping import project_motion  # the way back sits above the retargeter
    from motion2robot.retarget.api import solve_legs

    opt = options or RetargetOptions()
    if opt.fps is not None and abs(opt.fps - human.fps) > 1e-9:
        human = resample(human, opt.fps)
    inner = replace(opt, fps=None)
    meta, legs = motion.meta, legs_of(motion)
    tempo = float(meta.get("tempo") or 1.0)

    def solved(k: float) -> RobotMotion:
        return solve_legs(stretch(human, k), robot, inner, legs).with_(meta={"tempo": k})

    def exact_or_solved() -> RobotMotion:
        return exact_motion(human, robot, inner) or solve_legs(human, robot, inner, legs)

    replayed, retimed = _from(meta, "replayed"), _from(meta, "retimed")
    if replayed is not None:
        return solve_legs(project_motion(solved(replayed), robot, human), robot, inner, legs)
    if retimed is not None:
        base = exact_or_solved() if retimed == 1.0 and meta.get("reached") else solved(retimed)
        return retime(base, robot, tempo, human.num_frames)
    if meta.get("reached"):
        return exact_or_solved()
    return solved(tempo)

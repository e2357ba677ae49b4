"""Where balance must override the kept joints of a composed edit, and why.

The composed edit keeps every hinge driven by an unedited body part exactly at the source's robot
trajectory. That can break what neither motion breaks alone: the edit leans the torso while the
kept legs stay where the source's balance put them, and the CoM leaves the feet, or a kept knee
now carries 1.3x its torque. :func:`must_override` finds those frames: frames of the window where
the composed motion fails the balance or the torque check (kinematic checks, MuJoCo inverse
dynamics) while the source's robot motion passes there (else the source already failed: nothing
the edit could fix) and the edit's own whole-body solution passes too (else overriding would not
help: the edit itself is infeasible there). The three checks run on the same window of frames, so
they share its edge effects, and the source's contact labels (which the edited motion carries).
Frames are robot frames of the whole motion.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from motion2robot.robot_motion import RobotMotion
from motion2robot.util.ranges import frame_ranges

#: The checks balance may override kept joints for (the rest are the edit's own business).
CHECKS = ("balance", "torque_limits")
#: How many times the override may widen by the blend where the blend itself fails.
WIDEN_STEPS = 3


@dataclass(frozen=True)
class OverrideNeed:
    """frames: robot frames to override (sorted); why: sentences saying what the composed motion
    fails there; unresolved: frames where the composed motion fails and the edit's own solution
    fails too (overriding would not help); failing: {check: frames} of the composed motion."""

    frames: list[int]
    why: list[str]
    unresolved: list[int]
    failing: dict[str, list[int]]


def _failing(robot, like: RobotMotion, q: np.ndarray, window: tuple[int, int],
             checks: tuple[str, ...]) -> tuple[dict[str, set[int]], dict[str, dict]]:
    from motion2robot.validate import CheckOptions, check

    lo, hi = window
    labels = like.meta.get("contacts")
    meta = {"contacts": list(labels)[lo:hi]} if isinstance(labels, (list, tuple, np.ndarray)) else {}
    rep = check(RobotMotion(q[lo:hi], like.fps, like.joint_names, like.robot, meta), robot, CheckOptions(physics=False))
    return ({c: {lo + int(f) for f in rep.checks[c].get("frames", [])} for c in checks},
            {c: rep.checks[c] for c in checks})


def _why(name: str, c: dict, frames: list[int], lo: int, fps: float) -> list[str]:
    """Sentences for one failing check of the composed motion, restricted to ``frames``."""
    from motion2robot.validate.reasons import human_name

    where = f"in frames {frame_ranges(frames, 4)} (from {frames[0] / fps:.2f} s)"
    if name == "balance":
        worst = [(c[k]["by_m"], w) for k, w in (("zmp_worst", "the ZMP"), ("com_worst", "the CoM")) if c.get(k)]
        if worst:
            by, what = max(worst)
            return [f"balance: {what} leaves the support polygon by up to {by * 100:.1f} cm {where}"]
        return [f"balance: the support is lost {where}"]
    out = []
    for v in c.get("violations", []):
        mine = sorted({lo + int(f) for f in v["frames"]} & set(frames))
        if mine:
            out.append(f"torque: {human_name(v['joint'])} at {v['ratio']:.2f}x its torque limit "
                       f"in frames {frame_ranges(mine, 4)}")
    return out or [f"torque: a joint over its torque limit {where}"]


def must_override(robot, src: RobotMotion, q_comp: np.ndarray, q_edit: np.ndarray, window: tuple[int, int],
                  compose_with: Callable[[list[int]], np.ndarray], blend: int,
                  apply: bool = True) -> tuple[OverrideNeed, np.ndarray]:
    """(the frames where balance must override the kept joints, the motion with them overridden:
    ``compose_with(frames)``, or ``q_comp`` when none). See the module text; when the blend into
    the override itself fails the checks (the switch falls where one foot carries the robot), the
    override widens by the blend on that side, at most :data:`WIDEN_STEPS` times. ``apply=False``
    (the override forbidden): the frames where it would start, and ``q_comp``."""
    checks = CHECKS if src.meta.get("balance", True) else ("torque_limits",)
    comp, comp_checks = _failing(robot, src, q_comp, window, checks)
    if not any(comp.values()):
        return OverrideNeed([], [], [], {}), q_comp
    own, _ = _failing(robot, src, src.qpos, window, checks)
    new = {c: comp[c] - own[c] for c in checks}  # failures the composition brought
    failing = {c: sorted(f) for c, f in comp.items() if f}
    if not any(new.values()):
        return OverrideNeed([], [], [], failing), q_comp
    edit, _ = _failing(robot, src, q_edit, window, checks)
    frames = set().union(*(new[c] - edit[c] for c in checks))
    unresolved = sorted(set().union(*(new[c] & edit[c] for c in checks)))
    why = []
    for c in checks:
        mine = sorted(new[c] - edit[c])
        if mine:
            why += _why(c, comp_checks[c], mine, window[0], src.fps)
    if not frames or not apply:
        return OverrideNeed(sorted(frames), why, unresolved, failing), q_comp
    first = set(frames)
    q = compose_with(sorted(frames))
    for _ in range(WIDEN_STEPS):
        now, _ = _failing(robot, src, q, window, checks)
        bad = set().union(*(now[c] - own[c] - edit[c] for c in checks))
        if not bad:
            break
        grown = {f + d for f in bad for d in range(-blend, blend + 1)} & set(range(*window))
        if grown <= frames:
            break
        frames |= grown
        q = compose_with(sorted(frames))
    if frames != first:
        why.append(f"widened to frames {frame_ranges(sorted(frames), 4)}: the blend into the override failed "
                   f"the same checks in frames {frame_ranges(sorted(frames - first), 4)}")
    return OverrideNeed(sorted(frames), why, unresolved, failing), q

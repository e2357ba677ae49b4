"""The target correction (step 6 of :mod:`motion2robot.projection`): ``human'`` moved until its
retargeting is the robot motion it was made from."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from motion2robot.motion.human import HumanMotion
from motion2robot.projection.mapping import project_motion
from motion2robot.projection.maths import keep_bones
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion

#: Target of the correction rounds: RMS (rad) over frames and hinges between the robot motions of
#: the original and of ``human'``.
TOLERANCE = 1e-3
#: The first phase (against the solves alone, :func:`solver_stages`) stops at this fraction of
#: TOLERANCE.
SOLVER_TOLERANCE = 0.1
#: Correction rounds at most (each one retargeting at the chosen tempo and legs, no judging).
ROUNDS = 16
#: The rounds stop early when the last STALL_ROUNDS rounds lowered the best RMS met before them
#: by less than STALL_GAIN (a fraction): the correction has stalled (a motion whose pipeline
#: re-lays what it is given, like a ``steps`` result's footholds, does not converge).
STALL_ROUNDS = 3
STALL_GAIN = 0.05
#: Rounds remembered by the Anderson mixing of the correction.
MEMORY = 4
#: Damping of the first rounds' inverse attenuation (:mod:`~.attenuation`): they are aimed at
#: most 1 + 1/MU times as far as a plain round.
MU = 0.1
#: A round whose RMS exceeds OVERSHOOT x the best met overshot: the rounds go back to the best
#: ``human'`` and damp the inverse MU_GROWTH times more.
OVERSHOOT = 1.25
MU_GROWTH = 4.0
#: The largest damping tried: a correction that stalls at it stops.
MU_LAST = 2.0
#: How far a round may make a bone of ``human'`` longer or shorter than the direct mapping's
#: (a fraction, per frame and bone: :func:`~.maths.keep_bones`). Free, the rounds stretched arms
#: by up to 43 % (the lever that pulls a robot's elbow straighter than a straight target does)
#: and a sitting clip's legs to 3.8 m; held to the direct mapping's lengths, 28 of the 66 dev
#: clips came back within TOLERANCE where 35 did free; at 5 %, 33 (10 %: 32). MDM's own samples
#: vary their bones by 9-17 % at the 95th percentile.
BONE_SLACK = 0.05
#: Each overshoot also shortens the next rounds' steps by this factor (back to whole steps at the
#: next round that improves on the best): once the damping is high, a round from the best is the
#: plain step, and where that step overshoots it did so again every round (an MDM throw's first
#: phase spent 10 of its 16 rounds at 0.0137 rad from the best 0.0087).
REACH_SHRINK = 0.5


def hinge_rms(a: RobotMotion, b: RobotMotion) -> float:
    """RMS (rad) over frames and hinges of two robot motions of the same length (inf otherwise)."""
    if a.qpos.shape != b.qpos.shape:
        return float("inf")
    return float(np.sqrt(np.mean((a.qpos[:, 7:] - b.qpos[:, 7:]) ** 2)))


def anderson_step(xs: list[np.ndarray], fs: list[np.ndarray]) -> np.ndarray:
    """Next iterate of the fixed point x = x + f(x) by Anderson mixing over the history
    (``xs``, ``fs``: flattened iterates and their residuals, oldest first): the combination of
    the last iterates whose residuals cancel best (weights summing to 1, least squares), plus
    its residual. With one entry: the plain step x + f."""
    x, f = xs[-1], fs[-1]
    if len(xs) < 2:
        return x + f
    dF = np.stack([fs[i + 1] - fs[i] for i in range(len(fs) - 1)], axis=1)
    dX = np.stack([xs[i + 1] - xs[i] for i in range(len(xs) - 1)], axis=1)
    gamma, *_ = np.linalg.lstsq(dF, f, rcond=None)
    return x + f - (dX + dF) @ gamma


def refine(direct: HumanMotion, motion: RobotMotion, robot: Robot, solve: Callable[[HumanMotion], RobotMotion],
           rounds: int = ROUNDS, tolerance: float = TOLERANCE, memory: int = MEMORY,
           aim: Callable[[RobotMotion, float], RobotMotion] | None = None,
           reference: HumanMotion | None = None) -> tuple[HumanMotion, tuple[float, ...]]:
    """The target correction (step 6 of the projection module text): starting from ``direct`` (= P(motion)),
    solve the fixed point ``P(solve(h)) = P(motion)`` for ``h`` by Anderson-accelerated rounds of
    ``h <- h + (P(aim(q, mu)) - P(q))``, q = ``solve(h)`` (:func:`anderson_step`, the last
    ``memory`` rounds) until ``solve(h)`` is within ``tolerance`` rad RMS of ``motion`` or the
    rounds stall (STALL_ROUNDS, STALL_GAIN). ``aim(q, mu)``: the robot motion the round maps back,
    ``motion`` moved further by what the retargeting will not pass on
    (:meth:`~.attenuation.Attenuation.aim`, damped by ``mu``); None: ``motion`` itself (plain
    rounds). A round that ends more than OVERSHOOT times the best RMS met, or rounds that stall,
    go back to the best ``h`` with ``mu`` x MU_GROWTH and a fresh mixing history (stalled with
    ``mu`` at MU_LAST, they stop); an overshoot also shortens the rounds' steps by REACH_SHRINK
    until one improves on the best. Every round's ``h`` keeps the bones of ``reference`` (default
    ``direct``) within BONE_SLACK (:func:`~.maths.keep_bones`: each bone's direction as the round
    moved it, its length clipped). Returns the best ``h`` met and the RMS of every round tried (a
    round whose solve changes the frame count stops the rounds)."""
    shape = np.shape(direct.positions)
    bones = np.asarray((direct if reference is None else reference).positions)  # human' keeps the skeleton it was mapped back to
    h, errors = direct, []
    best: tuple[float, HumanMotion, RobotMotion | None] = (float("inf"), direct, None)
    mu, since, reach = MU, 0, 1.0
    xs: list[np.ndarray] = []
    fs: list[np.ndarray] = []
    for _ in range(max(1, rounds)):
        q = solve(h)
        err = hinge_rms(q, motion)
        errors.append(err)
        overshot = aim is not None and err > OVERSHOOT * best[0]
        if err < best[0]:
            best, reach = (err, h, q), 1.0
        elif overshot:  # the rounds from the best go a shorter way, until one improves on it
            reach *= REACH_SHRINK
        if err <= tolerance or not np.isfinite(err):
            break
        stalled = (not overshot and len(errors) - since > STALL_ROUNDS
                   and min(errors[-STALL_ROUNDS:]) > (1.0 - STALL_GAIN) * min(errors[:-STALL_ROUNDS]))
        if stalled and (aim is None or mu * MU_GROWTH > MU_LAST):
            break
        if overshot or stalled:  # from the best again, aimed less far (plainer rounds)
            mu *= MU_GROWTH
            h, q, xs, fs, since = best[1], best[2], [], [], len(errors)
        # compared at the scale this solve computed from h's bone lengths: the fixed point is in
        # the robot's space (keypoints equal), not at the original's scale
        target = motion if aim is None else aim(q, mu)
        goal = project_motion(target.with_(meta={"scale": q.meta["scale"]}), robot, h).positions
        xs.append(np.asarray(h.positions).ravel())
        fs.append((goal - project_motion(q, robot, h).positions).ravel())
        xs, fs = xs[-memory - 1:], fs[-memory - 1:]
        h = h.with_(positions=keep_bones((xs[-1] + reach * (anderson_step(xs, fs) - xs[-1])).reshape(shape), bones,
                                          BONE_SLACK))
    return best[1], tuple(errors)


def solver_stages(options: Any) -> Any:
    """``options`` (RetargetOptions, None = the defaults) with the whole-body pipeline cut after its
    solves (the free-feet and pinned stages): no servo rounds, joint smoothing, ZMP stage or root
    pass. The first phase of the target correction aims these at the robot motion: the later
    stages leave a motion that already passed through them almost as it is (0.0002 rad on an MDM
    throw), but switch on wherever a solve's small error crosses one of their thresholds. The
    ``steps`` pattern runs none of these but the smoothing (of the upper body it takes from the
    free solve: without it, only the exact velocity clamp)."""
    from dataclasses import replace

    from motion2robot.retarget.api import RetargetOptions

    return replace(options or RetargetOptions(), corrections=0, smoothing=False, dynamic_balance=False,
                   root_pass=False)


def chosen_solve(motion: RobotMotion, robot: Robot, options: Any) -> Callable[[HumanMotion], RobotMotion]:
    """The retargeting that made ``motion``, as one function of the human motion: its tempo factor
    (in the result's meta, key ``tempo``) and its legs, no judging: a ``steps`` result's by the ``steps`` pattern (corrected against the
    whole body instead, whose feet ``human'`` cannot steer onto the pattern's footholds, the
    rounds of the Bandai walk stalled at 0.068 rad), the others by the whole-body pipeline (a
    ``stance`` result's human' already stands in the stance, and whole body is what the legs
    policy tries first)."""
    from dataclasses import replace

    from motion2robot.motion.ops import resample
    from motion2robot.retarget.api import RetargetOptions, solve_legs
    from motion2robot.retarget.executable import legs_of
    from motion2robot.retarget.tempo import stretch

    opt = options or RetargetOptions()
    inner = replace(opt, fps=None)
    k = float(motion.meta.get("tempo") or 1.0)
    legs = "steps" if legs_of(motion) == "steps" else "whole"

    def solve(h: HumanMotion) -> RobotMotion:
        if opt.fps is not None and abs(opt.fps - h.fps) > 1e-9:
            h = resample(h, opt.fps)
        # its meta says the tempo, as the policy's does: the way back maps human frame i to robot
        # frame i * k (without it, frame i, and the rounds of a slowed clip compared the wrong frames)
        return solve_legs(stretch(h, k), robot, inner, legs).with_(meta={"tempo": k})

    return solve

"""``retarget(human, robot, options) -> RobotMotion``: the whole pipeline in memory.

:func:`whole_body` reads as the pipeline it is; each stage lives in its own module:

1. setup (:mod:`~.setup`): the compiled problem, the human keypoints scaled to the robot
   (:mod:`~.scale`), the contact labels, the weights at the clip's rate;
2. free-feet solve (:func:`~.solve_stages.free_solve`): batched LM, soles only asked to touch
   the floor in contact frames;
3. contact plan (:mod:`~.contact_plan`): each contact phase's placement, the plan of every sole
   in every frame (:mod:`~.footsteps`: stance pinned, swings lifted clear of the floor and of the
   other foot), the shrunk support polygons;
4. pinned solve (:func:`~.solve_stages.pinned_solve`): every sole corner on its plan, the CoM
   over the support polygon;
5. servo rounds (:func:`~.solve_stages.servo_rounds`): smoothing to what the servos can follow,
   projection onto the hard constraints, the exact velocity clamp;
6. joint smoothing (:func:`~.solve_stages.joint_smoothing`): one filter over root and hinges,
   projection back onto the hard constraints;
7. dynamic balance (:mod:`~.balance_stage`): the ZMP inside the soles by a planned CoM path
   (kept only where it helps);
8. root pass (:mod:`~.root_pass`): the root alone moved so no sole corner is below the floor and
   the stance sole neither slides nor spins;
9. result (:mod:`~.result`): per-frame figures into ``meta["solver"]``.

:func:`retarget` wraps :func:`whole_body` (or the ``steps`` pattern of :mod:`~.gait`, or the
``stance`` of :mod:`~.stance`: :func:`solve_legs`) in the tempo and legs policy of
:mod:`~motion2robot.retarget.executable` (attempts judged by ``check``). :func:`whole_body` is
:func:`finish` of :func:`solves` (stages 1-4, then 5-9): the policy measures a stance after its
solves and, when it judges it, goes on from them.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from motion2robot.motion.human import HumanMotion
from motion2robot.motion.ops import resample
from motion2robot.retarget.balance_stage import dynamic_balance
from motion2robot.retarget.contact_plan import ContactPlan, plan_contacts
from motion2robot.retarget.exact import exact_motion
from motion2robot.retarget.executable import plan
from motion2robot.retarget.finite import check_solution
from motion2robot.retarget.gait import Footing, footing, steps
from motion2robot.retarget.options import LEGS, RetargetOptions
from motion2robot.retarget.result import StageFigures, robot_motion
from motion2robot.retarget.root_pass import root_shift
from motion2robot.retarget.setup import Setup, prepare, require_solvable
from motion2robot.retarget.solve_stages import free_solve, joint_smoothing, pinned_solve, servo_rounds
from motion2robot.retarget.stance import stance
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion

__all__ = ["LEGS", "RetargetOptions", "retarget", "retarget_and_check", "whole_body"]


def retarget(human: HumanMotion, robot: Robot, options: RetargetOptions | None = None) -> RobotMotion:
    """Retarget a canonical human motion onto ``robot`` at the tempo and with the legs the options
    ask for (by default the first that passes ``check``: see
    :mod:`~motion2robot.retarget.executable`); the result's meta carries the scale, the contacts
    used, the scaled human root path, the solver's figures, the tempo and the fallback taken."""
    return retarget_and_check(human, robot, options)[0]


def retarget_and_check(human: HumanMotion, robot: Robot, options: RetargetOptions | None = None,
                       check_options: object | None = None) -> tuple[RobotMotion, object | None]:
    """:func:`retarget`, also returning the ``check`` report of the chosen attempt (None when the
    policy judged nothing: fixed tempo and legs); ``check_options`` are the judge's."""
    opt = options or RetargetOptions()
    if opt.fps is not None and abs(opt.fps - human.fps) > 1e-9:
        human = resample(human, opt.fps)
    require_solvable(human)
    inner = replace(opt, fps=None)
    probed: list[tuple[HumanMotion, Footing]] = []  # plan probes once; the steps of that motion reuse it

    def probe(h: HumanMotion) -> float:
        probed.append((h, footing(h, robot, inner)))
        return probed[-1][1].factor

    sketched: dict[int, Solved] = {}  # the stance's solves the comparison measured; its attempt goes on from them

    def sketch(h: HumanMotion) -> RobotMotion:
        sketched[id(h)] = solves(stance(h), robot, inner)
        return sketched[id(h)].motion()

    def solve(h: HumanMotion, legs: str) -> RobotMotion:
        if legs == "steps" and probed and probed[0][0] is h:
            return steps(h, robot, inner, probed.pop()[1])
        if legs == "stance" and id(h) in sketched:
            return finish(sketched.pop(id(h)))
        return solve_legs(h, robot, inner, legs)

    def replay(motion: RobotMotion) -> HumanMotion:
        from motion2robot.projection.mapping import project_motion  # the way back sits above the retargeter

        return project_motion(motion, robot, human)

    reached = exact_motion(human, robot, inner) if opt.legs == "auto" else None
    return plan(human, robot, opt.tempo, opt.legs, opt.tempo_cap, solve, check_options, probe, sketch, reached,
                replay if opt.replay else None)


def solve_legs(human: HumanMotion, robot: Robot, options: RetargetOptions, legs: str) -> RobotMotion:
    """The robot motion of one legs mode at the human's own tempo: ``whole`` body
    (:func:`whole_body`), ``steps`` (:func:`~.gait.steps`) or ``stance``
    (:func:`~.stance.stance`, then the whole body)."""
    if legs == "steps":
        return steps(human, robot, options)
    return whole_body(stance(human) if legs == "stance" else human, robot, options)


@dataclass(frozen=True)
class Solved:
    """The whole-body pipeline after its solves (stages 1-4 of the module text): the trajectory
    ``Q`` (T, nq) and what stages 5-9 go on from (:func:`finish`)."""

    setup: Setup
    contacts: ContactPlan
    Q: np.ndarray
    free: object
    pinned: object
    started: tuple[float, float]  # perf_counter at the start and at the solves' start

    def motion(self) -> RobotMotion:
        """``Q`` as a robot motion without meta (to measure it, not to play it)."""
        return RobotMotion(qpos=self.Q, fps=self.setup.fps, joint_names=self.setup.robot.joint_names,
                           robot=self.setup.robot.name)


def solves(human: HumanMotion, robot: Robot, options: RetargetOptions | None = None) -> Solved:
    """Stages 1-4 of the whole-body pipeline on ``human`` at its own tempo."""
    opt = options or RetargetOptions()
    if opt.fps is not None and abs(opt.fps - human.fps) > 1e-9:
        human = resample(human, opt.fps)
    t_all = time.perf_counter()
    setup = prepare(human, robot, opt)
    t_solve = time.perf_counter()
    Q, free = free_solve(setup)
    contacts = plan_contacts(setup, setup.points(Q)[1])
    Q, pinned = pinned_solve(setup, contacts, Q)
    return Solved(setup, contacts, Q, free, pinned, (t_all, t_solve))


def finish(solved: Solved) -> RobotMotion:
    """Stages 5-9 of the whole-body pipeline, from its solves."""
    setup, contacts, Q, opt = solved.setup, solved.contacts, solved.Q, solved.setup.opt
    Q, rounds = servo_rounds(setup, contacts, Q)
    if opt.smoothing:
        Q = joint_smoothing(setup, contacts, Q)
    zmp = None
    if opt.balance and opt.dynamic_balance and opt.contacts:
        Q, zmp = dynamic_balance(setup, contacts, Q)
    pts = setup.points(Q)
    shift = None
    if opt.root_pass:  # joints final: move only the root onto the floor / stance anchors
        shift = root_shift(pts[1], contacts.labels, setup.fps, setup.root_target, hold_yaw=opt.hold_stance_yaw)
        Q = shift.apply(Q)  # a rigid root motion moves every point with it; the capsule gaps stay
        pts = (shift.points(pts[0]), shift.points(pts[1]), shift.points(pts[2][:, None])[:, 0], pts[3])
    t_all, t_solve = solved.started
    solve_s = time.perf_counter() - t_solve
    check_solution(Q, setup.robot.joint_names, setup.where)
    stages = StageFigures(solved.free, solved.pinned, rounds, zmp, shift.figures() if shift is not None else None,
                          solve_s, time.perf_counter() - t_all)
    return robot_motion(setup, contacts, Q, pts, stages, shift is not None)


def whole_body(human: HumanMotion, robot: Robot, options: RetargetOptions | None = None) -> RobotMotion:
    """The whole-body pipeline (stages 1-9 of the module text) on ``human`` at its own tempo; a
    robot-shaped ``human`` (:mod:`~.reach`) is reached exactly instead (:func:`~.exact.exact_motion`)."""
    return exact_motion(human, robot, options) or finish(solves(human, robot, options))

"""The robot motion of a robot-shaped human motion: its exact poses (:mod:`~.reach`), with the
meta every whole-body result carries (scale, contacts, per-frame figures), in place of the
solves and the stages after them (which exist to bring a solve's pose nearer to what the
servos can follow; a motion that reaches every target exactly is judged by ``check`` as it is).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from motion2robot.motion.human import HumanMotion
from motion2robot.retarget.contact_plan import plan_contacts
from motion2robot.retarget.finite import check_solution
from motion2robot.retarget.options import RetargetOptions
from motion2robot.retarget.reach import TOLERANCE_M, robot_shaped
from motion2robot.retarget.result import StageFigures, robot_motion
from motion2robot.retarget.setup import prepare
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion


@dataclass(frozen=True)
class _NoSolve:
    iterations: int = 0


def exact_motion(human: HumanMotion, robot: Robot, options: RetargetOptions | None = None) -> RobotMotion | None:
    """The exact poses of ``human`` (canonical, at its output rate) as a robot motion, or None
    when ``human`` is not robot-shaped for ``robot`` (or ``options.reach`` is off)."""
    opt = options or RetargetOptions()
    if not opt.reach or not np.all(np.isfinite(human.positions)) or human.num_frames < 2:
        return None
    t_all = time.perf_counter()
    found = robot_shaped(human.positions, robot, opt.scale)
    if found is None:
        return None
    scale, Q = found
    setup = prepare(human, robot, replace(opt, scale=scale))
    check_solution(Q, robot.joint_names, setup.where)
    pts = setup.points(Q)
    contacts = plan_contacts(setup, pts[1])
    total = time.perf_counter() - t_all
    motion = robot_motion(setup, contacts, Q, pts, StageFigures(_NoSolve(), None, 0, None, None, total, total), False)
    solver = {**motion.meta["solver"], "method": "exact reach (Gauss-Newton on the keypoints, frame by frame)",
              "reached": {"tolerance_m": TOLERANCE_M, "max_residual_m": motion.meta["solver"]["max_residual"]}}
    return motion.with_(meta={"solver": solver, "reached": True})

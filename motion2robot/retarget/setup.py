"""What every stage of the whole-body pipeline reads: the compiled problem, the scaled human
keypoints, the contact labels, the limits and the weights at the clip's rate (:class:`Setup`).

Units: metres, radians, seconds; world frame z up.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from motion2robot.errors import SolverError
from motion2robot.motion.human import SMPL22, HumanMotion
from motion2robot.retarget import native
from motion2robot.retarget.compiled import CompiledProblem, compiled_problem
from motion2robot.retarget.contacts import contact_labels, planted
from motion2robot.retarget.costs import Weights
from motion2robot.retarget.finite import check_targets
from motion2robot.retarget.options import RetargetOptions
from motion2robot.retarget.scale import Scale, auto_scale, scaled_keypoints
from motion2robot.retarget.smoothing import root_acceleration_target, servo_targets
from motion2robot.robot.robot import Robot

#: fps at which the temporal weights apply as given (see :func:`rate_weights`).
TEMPORAL_REFERENCE_FPS = 20.0


def rate_weights(w: Weights, fps: float) -> Weights:
    """The temporal weights act on per-frame differences, which shrink as the rate grows: scaled by
    (fps / TEMPORAL_REFERENCE_FPS)^2 so a finer output rate does not loosen them (at 100 fps
    unscaled, a byebye's peak joint acceleration grew 1.6x over the native 30 fps; scaled, 0.6x)."""
    k = (fps / TEMPORAL_REFERENCE_FPS) ** 2
    return replace(w, velocity=w.velocity * k, acceleration=w.acceleration * k)


def require_solvable(human: HumanMotion) -> None:
    """SolverError (a user error) for clips no stage can retarget."""
    where = human.meta.get("source", "the motion")
    if human.num_frames < 2:
        raise SolverError(f"{where}: the clip has {human.num_frames} frame; retargeting needs at least 2 frames "
                          "(velocity limits, contacts)")
    if not np.all(np.isfinite(human.positions)):
        raise SolverError(f"{where}: keypoints contain NaN/inf; fix or trim the clip")


@dataclass(frozen=True)
class Setup:
    """human: the motion as solved (at its own rate); kp: (T, 22, 3) scaled keypoints (robot
    metres); labels: (T, 2) planted contact frames [left, right] of the human; weights: at the
    clip's rate; max_step: (n,) rad per frame the servos can move; servo: (speed, acceleration)
    smoothing targets per hinge; root_target: m/s^2 the root's acceleration is smoothed to (None
    without balance or smoothing); solve: the batched LM (or the IPOPT baseline)."""

    human: HumanMotion
    robot: Robot
    opt: RetargetOptions
    problem: CompiledProblem
    weights: Weights
    scale: Scale
    kp: np.ndarray
    labels: np.ndarray
    label_source: str
    heel_up: int
    max_step: np.ndarray
    servo: tuple[np.ndarray, np.ndarray]
    root_target: float | None
    solve: Callable

    @property
    def fps(self) -> float:
        return self.human.fps

    @property
    def where(self) -> str:
        return self.human.meta.get("source", "the motion")

    def points(self, Q: np.ndarray) -> tuple[np.ndarray, ...]:
        """Keypoints (T, k, 3), sole corners (T, 2, 4, 3), CoM (T, 3) and capsule gaps (T, g) of ``Q``."""
        T = len(Q)
        kp, corners, com, gaps = self.problem.points_eval(T)(Q)
        return kp.reshape(T, -1, 3), corners.reshape(T, 2, 4, 3), com.reshape(T, 3), gaps.reshape(T, -1)


def prepare(human: HumanMotion, robot: Robot, opt: RetargetOptions) -> Setup:
    """The :class:`Setup` of ``human`` (already at its output rate) on ``robot``."""
    require_solvable(human)
    problem = compiled_problem(robot, opt.backend)
    native.library()  # the smoothing/clamp kernels: built on first use, like the problem's code
    scale = opt.scale or auto_scale(human, robot)
    kp = scaled_keypoints(human.positions, scale)
    check_targets(kp, SMPL22, human.meta.get("source", "the motion"))
    if opt.contacts:
        labels, source = contact_labels(human)
        heel_up = int(labels.sum())
        labels = planted(labels, human)
        heel_up -= int(labels.sum())
    else:
        heel_up, labels, source = 0, np.zeros((human.num_frames, 2), dtype=bool), "off"
    if opt.solver not in ("fast", "ipopt"):
        raise SolverError(f"unknown solver {opt.solver!r}; use 'fast' or 'ipopt'")
    if opt.solver == "ipopt":
        from motion2robot.retarget.baseline import solve_ipopt as solve
    else:
        from motion2robot.retarget.solver import solve
    root_target = root_acceleration_target(robot) if opt.balance and opt.smoothing else None
    return Setup(human, robot, opt, problem, rate_weights(opt.weights, human.fps), scale, kp, labels, source,
                 heel_up, robot.velocity_limit / human.fps, servo_targets(robot), root_target, solve)

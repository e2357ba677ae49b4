"""Servo sag and its feed-forward compensation: what angles the servos are asked for.

A position servo under a load torque tau settles tau / kp short of its goal (kp in N*m/rad). With
sag compensation the goal of every hinge is the planned angle plus the deflection the planned
motion's own torques will cause::

    goal = q_planned + clip(tau_ff, -torque_limit, torque_limit) / kp

with tau_ff the hinge torques of the planned motion by inverse dynamics
(:func:`~motion2robot.validate.dynamics.inverse_dynamics`: gravity, inertia, the floor reaction
spread over the soles in contact and, with ``servo_dynamics``, the servo's own rotor inertia and
damping); a torque beyond the servo's limit cannot be held whatever the goal, hence the clip.
Both the physics rollout of ``check`` (option ``sag_compensation``) and ``stream
--sag-compensation`` take their targets from here. Angles in radians, ``joint_names`` order.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from motion2robot.errors import InputFileError
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate.context import Context, prepare
from motion2robot.validate.options import CheckOptions


def sag_offsets(tau: np.ndarray, robot: Robot) -> np.ndarray:
    """(T, n) rad each servo sags under the hinge torques ``tau`` (T, n) N*m (clipped to its limit)."""
    limit = np.asarray(robot.torque_limit, dtype=np.float64)
    return np.clip(tau, -limit, limit) / np.asarray(robot.kp, dtype=np.float64)


def servo_targets(ctx: Context, compensate: bool) -> np.ndarray:
    """(T, n) rad the servos are asked for: the planned joint angles of ``ctx.motion``, plus the
    predicted sag when ``compensate``."""
    q = ctx.kin.qpos[:, 7:]
    return q + sag_offsets(ctx.dyn.tau, ctx.robot) if compensate else q.copy()


def compensated_motion(motion: RobotMotion, robot: Robot, options: CheckOptions | None = None) -> RobotMotion:
    """``motion`` with its joint angles replaced by the sag-compensated servo targets (root and
    timing unchanged; ``meta["sag_compensation"]`` = the largest offset in rad), for streaming.
    ``options`` sets the inverse dynamics' contact model as ``check`` would (default options)."""
    if tuple(motion.joint_names) != tuple(robot.joint_names):
        raise InputFileError(f"motion for robot {motion.robot!r} does not have the joints of robot {robot.name!r}; "
                             f"sag compensation needs the robot it was made for (--robot {motion.robot})")
    opts = replace(options or CheckOptions(), physics=False)
    ctx = prepare(motion, robot, opts)
    qpos = ctx.kin.qpos.copy()
    qpos[:, 7:] = servo_targets(ctx, True)
    meta = dict(motion.meta)
    meta["sag_compensation"] = round(float(np.abs(qpos[:, 7:] - ctx.kin.qpos[:, 7:]).max(initial=0.0)), 4)
    return RobotMotion(qpos, motion.fps, motion.joint_names, motion.robot, meta=meta)

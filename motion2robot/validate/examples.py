"""Constructed robot motions with known verdicts, for tests, benchmarks and demonstrations.

All start from ``robot.nominal_qpos`` (soles flat on the floor) and are sampled at ``fps``:

- :func:`standing`: the nominal posture held (feasible);
- :func:`waving`: standing while one arm waves gently (feasible);
- :func:`knee_past_limit`: standing, with the left knee set past its upper limit in frames
  ``first..last`` (fails ``joint_limits`` in exactly those frames);
- :func:`arm_through_torso`: the left arm rolls inwards through the torso and back (fails
  ``self_collision``);
- :func:`slow_lean`: the whole body tips backwards about the ankles, soles flat, until the CoM
  leaves the feet (fails ``balance``; falls in the physics playback).

They assume an OP3-like joint naming (``l_knee``, ``l_sho_roll``, ``l_el``, ``l_ank_pitch``...)
and the bundled OP3's joint sign conventions.
"""

from __future__ import annotations

import mujoco
import numpy as np

from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion


def _motion(robot: Robot, q: np.ndarray, fps: float, what: str) -> RobotMotion:
    return RobotMotion(q, fps, robot.joint_names, robot.name, meta={"source": f"constructed: {what}",
                                                                   "robot_hash": robot.model_hash})


def _hold(robot: Robot, seconds: float, fps: float) -> np.ndarray:
    return np.tile(robot.nominal_qpos, (max(round(seconds * fps), 2), 1))


def standing(robot: Robot, seconds: float = 2.0, fps: float = 50.0) -> RobotMotion:
    return _motion(robot, _hold(robot, seconds, fps), fps, "standing")


def waving(robot: Robot, seconds: float = 3.0, fps: float = 50.0) -> RobotMotion:
    """Left arm raised sideways (shoulder roll eased from nominal towards horizontal) while the
    elbow waves +-0.3 rad at 1 Hz."""
    q = _hold(robot, seconds, fps)
    t = np.arange(len(q)) / fps
    roll, el = 7 + robot.joint_index("l_sho_roll"), 7 + robot.joint_index("l_el")
    ease = 0.5 - 0.5 * np.cos(np.pi * np.clip(t / 1.0, 0.0, 1.0))  # 0 -> 1 over the first second
    q[:, roll] = q[0, roll] + ease * (0.2 - q[0, roll])
    q[:, el] = -0.6 + 0.3 * ease * np.sin(2 * np.pi * 1.0 * t)
    q[:, el] = np.clip(q[:, el], robot.lower[el - 7], robot.upper[el - 7])
    return _motion(robot, q, fps, "waving")


def knee_past_limit(robot: Robot, first: int = 10, last: int = 20, excess: float = 0.2,
                    frames: int = 40, fps: float = 50.0) -> RobotMotion:
    """Standing; the left knee at ``upper + excess`` (rad) in frames first..last inclusive."""
    q = _hold(robot, frames / fps, fps)
    j = robot.joint_index("l_knee")
    q[first:last + 1, 7 + j] = robot.upper[j] + excess
    return _motion(robot, q, fps, "knee past its limit")


def arm_through_torso(robot: Robot, seconds: float = 2.0, fps: float = 50.0, reach: float = 2.3) -> RobotMotion:
    """The left shoulder roll swings from nominal to ``reach`` rad (through the torso) and back,
    the elbow folded."""
    q = _hold(robot, seconds, fps)
    t = np.arange(len(q)) / fps
    roll, el = 7 + robot.joint_index("l_sho_roll"), 7 + robot.joint_index("l_el")
    s = 0.5 - 0.5 * np.cos(2 * np.pi * t / seconds)  # 0 -> 1 -> 0
    q[:, roll] = q[0, roll] + s * (reach - q[0, roll])
    q[:, el] = q[0, el] + s * (-1.2 - q[0, el])
    return _motion(robot, q, fps, "arm through the torso")


def _pitch_quat(angle: float) -> np.ndarray:
    return np.array([np.cos(angle / 2), 0.0, np.sin(angle / 2), 0.0])


def slow_lean(robot: Robot, angle: float = -0.35, lean_seconds: float = 2.0, hold_seconds: float = 1.0,
              fps: float = 50.0) -> RobotMotion:
    """The body tips by ``angle`` rad about the y axis (negative = backwards) through the ankles,
    linearly over ``lean_seconds``, then holds; the ankle pitches counter-rotate so the soles stay
    flat, and the root moves so the left sole centre stays where it started."""
    n_lean, n_hold = round(lean_seconds * fps), round(hold_seconds * fps)
    theta = np.concatenate([np.linspace(0.0, angle, n_lean), np.full(n_hold, angle)])
    m = robot.model
    d = mujoco.MjData(m)
    q0 = robot.nominal_qpos.copy()
    sole = int(robot.sole_center_sites[0])
    d.qpos[:] = q0
    mujoco.mj_kinematics(m, d)
    anchor = d.site_xpos[sole].copy()
    la, ra = 7 + robot.joint_index("l_ank_pitch"), 7 + robot.joint_index("r_ank_pitch")
    out = np.empty((len(theta), m.nq))
    for i, th in enumerate(theta):
        q = q0.copy()
        q[3:7] = _pitch_quat(th)  # nominal root is upright (identity)
        q[la] = q0[la] + th  # left ankle pitch axis is -y, right +y (OP3): soles stay flat
        q[ra] = q0[ra] - th
        q[:3] = 0.0
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        q[:3] = anchor - d.site_xpos[sole]
        out[i] = q
    return _motion(robot, out, fps, "slow lean")

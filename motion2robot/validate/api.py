"""``check(motion, robot, options) -> FeasibilityReport``: run every check on a RobotMotion."""

from __future__ import annotations

import time

import numpy as np

from motion2robot.errors import InputFileError
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.util.ranges import frame_ranges
from motion2robot.validate.balance import balance, margins
from motion2robot.validate.collision import self_collision
from motion2robot.validate.context import Context, prepare
from motion2robot.validate.ground import ground
from motion2robot.validate.limits import (
    acceleration,
    joint_limits,
    torque_limits,
    velocity_limits,
)
from motion2robot.validate.options import CheckOptions
from motion2robot.validate.reasons import reasons
from motion2robot.validate.report import FeasibilityReport, verdict
from motion2robot.validate.rollout import play, rollout
from motion2robot.validate.trajectory import trajectory


def _require_match(motion: RobotMotion, robot: Robot) -> None:
    if tuple(motion.joint_names) != tuple(robot.joint_names):
        raise InputFileError(
            f"motion for robot {motion.robot!r} has joints {', '.join(motion.joint_names[:4])}... which do not match "
            f"robot {robot.name!r}; pass the robot it was made for (--robot {motion.robot})")
    if not np.isfinite(motion.qpos).all():
        bad = np.flatnonzero(~np.isfinite(motion.qpos).all(axis=1))
        raise InputFileError(f"motion for {motion.robot!r} has NaN/inf in frames {frame_ranges(bad)}; retarget again")
    if motion.num_frames < 1 or not motion.fps > 0:
        raise InputFileError(f"motion for {motion.robot!r} has {motion.num_frames} frames at {motion.fps} fps; nothing to check")


def kinematic_checks(ctx: Context) -> tuple[dict[str, dict], tuple[np.ndarray, np.ndarray]]:
    """Every check except the physics playback and the trajectory figure, plus the balance margins."""
    com_zmp = margins(ctx)
    checks = {
        "joint_limits": joint_limits(ctx),
        "velocity_limits": velocity_limits(ctx),
        "acceleration": acceleration(ctx),
        "torque_limits": torque_limits(ctx),
        "self_collision": self_collision(ctx),
        "ground": ground(ctx),
        "balance": balance(ctx, com_zmp),
    }
    return checks, com_zmp


def check(motion: RobotMotion, robot: Robot, options: CheckOptions | None = None, *,
          physics_if_feasible: bool = False) -> FeasibilityReport:
    """Judge ``motion`` on ``robot`` (see :class:`CheckOptions` for the thresholds).

    physics_if_feasible: skip the physics playback when a kinematic check already fails (the
    verdict is INFEASIBLE either way; for searches that judge many attempts)."""
    options = options or CheckOptions()
    _require_match(motion, robot)
    t0 = time.perf_counter()
    ctx = prepare(motion, robot, options)
    checks, (com_m, zmp_m) = kinematic_checks(ctx)
    t_kin = time.perf_counter() - t0
    kin, dyn = ctx.kin, ctx.dyn
    series = {
        "q": kin.qpos[:, 7:], "qvel": kin.qvel[:, 6:],
        "torque_ratio": np.abs(dyn.tau) / np.asarray(robot.torque_limit),
        "com_xy": kin.com[:, :2], "zmp_xy": dyn.zmp_xy, "support_margin": com_m, "zmp_margin": zmp_m,
        "foot_height": kin.corners[..., 2].min(axis=2), "contacts": ctx.support.any(axis=2),
    }
    pb = None
    kinematic_fail = physics_if_feasible and not all(c.get("ok", True) for c in checks.values())
    if options.physics and motion.num_frames >= 2 and not kinematic_fail:
        pb = play(ctx)
        checks["rollout"] = rollout(ctx, pb)
        series.update(rollout_q=pb.q, rollout_time=pb.time, torso_height=pb.torso_height, rollout_qpos=pb.qpos)
    else:
        why = ("--no-physics" if not options.physics else "a kinematic check already fails" if kinematic_fail
               else "a single frame has no playback")
        checks["rollout"] = {"ok": True, "skipped": why, "frames": []}
    checks["trajectory"] = trajectory(ctx, None if pb is None else pb.qpos[:, :2])
    figures = {
        "duration_s": round(motion.duration, 3),
        "check_time_s": round(time.perf_counter() - t0, 3),
        "kinematic_time_s": round(t_kin, 4),
        "max_torque_ratio": checks["torque_limits"]["max_ratio"],
        "min_zmp_margin_m": checks["balance"]["min_zmp_margin_m"],
        "min_com_margin_m": checks["balance"]["min_com_margin_m"],
        "failed": [n for n, c in checks.items() if n != "trajectory" and not c.get("skipped") and not c["ok"]],
        "robot_hash": robot.model_hash,
        "motion_robot_hash": motion.meta.get("robot_hash"),
        # how the motion was made executable (1.0 and None for motions made before the policy)
        "tempo": float(motion.meta.get("tempo", 1.0)),
        "tempo_reason": motion.meta.get("tempo_reason"),
        "fallback": motion.meta.get("fallback"),
    }
    if pb is not None:
        figures["playback_realtime_factor"] = checks["rollout"]["realtime_factor"]
    return FeasibilityReport(
        feasible=verdict(checks), checks=checks, reasons=reasons(checks, kin.fps), figures=figures,
        robot=robot.name, fps=float(motion.fps), frames=motion.num_frames, series=series)

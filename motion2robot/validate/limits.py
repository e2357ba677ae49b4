"""Joint range, speed and acceleration against the robot's limits.

Each check returns ``{"ok", "frames", <figures>, "violations": [...]}``; a violation names the
joint, the worst excess and the frames, and :mod:`~motion2robot.validate.reasons` words it.
"""

from __future__ import annotations

import numpy as np

from motion2robot.validate.context import Context
from motion2robot.validate.frames import frame_list, keep_runs
from motion2robot.validate.options import DEFAULT_ACCELERATION

#: Relative slack on the speed, acceleration and torque ratios (a trajectory clamped exactly at a
#: limit by the retargeter must not fail on rounding).
RATIO_TOLERANCE = 1e-3


def _per_joint(ctx: Context, bad: np.ndarray, value: np.ndarray, **fields) -> list[dict]:
    """One violation dict per joint with any bad frame: peak |value| over its bad frames."""
    out = []
    for j in np.flatnonzero(bad.any(axis=0)):
        rows = np.flatnonzero(bad[:, j])
        k = rows[np.argmax(np.abs(value[rows, j]))]
        item = {"joint": ctx.robot.joint_names[j], "frames": [int(r) for r in rows], "worst_frame": int(k)}
        for key, arr in fields.items():
            item[key] = round(float(arr[k, j] if np.ndim(arr) == 2 else arr[j]), 4)
        out.append(item)
    return sorted(out, key=lambda v: -abs(v.get("ratio", v.get("by_rad", 0.0))))


def joint_limits(ctx: Context) -> dict:
    """Frames and joints outside [lower, upper] by more than ``limit_tolerance``, and by how much (rad)."""
    q = ctx.kin.qpos[:, 7:]
    lo, hi = np.asarray(ctx.robot.lower), np.asarray(ctx.robot.upper)
    excess = np.maximum(lo - q, q - hi)  # > 0 outside
    bad = excess > ctx.options.limit_tolerance
    viol = _per_joint(ctx, bad, excess, by_rad=excess, value_rad=q, lower_rad=lo, upper_rad=hi)
    return {"ok": not bad.any(), "frames": frame_list(bad),
            "max_excess_rad": round(float(max(excess.max(), 0.0)), 4) if excess.size else 0.0,
            "violations": viol}


def velocity_limits(ctx: Context) -> dict:
    """Joint speed (central differences) against ``velocity_limit * velocity_margin`` (rad/s)."""
    limit = np.asarray(ctx.robot.velocity_limit) * ctx.options.velocity_margin
    return _against_limit(ctx, ctx.kin.qvel[:, 6:], limit, "rad_s", 3)


def _against_limit(ctx: Context, value: np.ndarray, limit: np.ndarray, unit: str, digits: int) -> dict:
    """The verdict of |value| (T, n) against a per-joint ``limit``: frames over it (runs of at least
    ``min_run``), per-joint violations with ``peak_<unit>``/``limit_<unit>``, and the maxima."""
    mag = np.abs(value)
    ratio = mag / limit
    bad = keep_runs(ratio > 1.0 + RATIO_TOLERANCE, ctx.options.min_run)
    viol = _per_joint(ctx, bad, ratio, ratio=ratio, **{f"peak_{unit}": mag, f"limit_{unit}": limit})
    return {"ok": not bad.any(), "frames": frame_list(bad),
            "max_ratio": round(float(ratio.max()), 3) if ratio.size else 0.0,
            f"max_{unit}": round(float(mag.max()), digits) if mag.size else 0.0,
            "violations": viol}


def acceleration_limits(robot_model, joint_ids, torque_limit, override: float | None) -> np.ndarray:
    """Per-joint acceleration limit (rad/s^2): ``override``, else torque_limit / armature."""
    if override is not None:
        return np.full(len(joint_ids), float(override))
    arm = robot_model.dof_armature[robot_model.jnt_dofadr[np.asarray(joint_ids)]]
    return np.where(arm > 0, np.asarray(torque_limit) / np.where(arm > 0, arm, 1.0), DEFAULT_ACCELERATION)


def acceleration(ctx: Context) -> dict:
    """Acceleration spikes: |qacc| above the joint's acceleration limit (see :class:`CheckOptions`)."""
    limit = acceleration_limits(ctx.robot.model, ctx.robot.joint_ids, ctx.robot.torque_limit,
                                ctx.options.acceleration_limit)
    return _against_limit(ctx, ctx.kin.qacc[:, 6:], limit, "rad_s2", 2)


def torque_limits(ctx: Context) -> dict:
    """Inverse-dynamics torque per joint (see :mod:`~motion2robot.validate.dynamics`) against
    ``torque_limit * torque_margin``, as a ratio."""
    tau = ctx.dyn.tau
    limit = np.asarray(ctx.robot.torque_limit) * ctx.options.torque_margin
    ratio = np.abs(tau) / limit
    bad = keep_runs(ratio > 1.0 + RATIO_TOLERANCE, ctx.options.min_run)
    viol = _per_joint(ctx, bad, ratio, ratio=ratio, peak_nm=np.abs(tau), limit_nm=limit,
                      servo_nm=np.abs(ctx.dyn.servo_tau), qvel_rad_s=np.abs(ctx.kin.qvel[:, 6:]))
    worst = int(np.argmax(ratio.max(axis=0))) if ratio.size else 0
    return {"ok": not bad.any(), "frames": frame_list(bad),
            "max_ratio": round(float(ratio.max()), 3) if ratio.size else 0.0,
            "worst_joint": ctx.robot.joint_names[worst] if ratio.size else None,
            "mean_ratio": round(float(ratio.mean()), 3) if ratio.size else 0.0,
            "method": "mj_rne inverse dynamics with finite-difference velocities/accelerations; floor reaction "
                      "from the supporting sole corners, each corner force inside the friction cone (so the centre of "
                      "pressure stays on the soles), distributed to minimise the hinge torques"
                      + ("; the servo's armature * qacc + damping * qvel added" if ctx.options.servo_dynamics else ""),
            "violations": viol}

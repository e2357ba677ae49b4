"""Benchmark of ``motion2robot check``: frames/s of the kinematic + balance + torque checks and the
physics playback's real-time factor, on a ~2,000-frame motion of the bundled OP3.

The contact-force solve (friction cones, centre of pressure on the sole: issue #19) is timed on
its own, beside the contact model it replaced (normal forces >= 0, friction without a limit),
which is loaded from git history (``--old-model REV``, default the commit before it) and run on
the same kinematics in the same run; the whole check's rate with the old model is the measured
rate with the difference of the two solves' times taken off.

The motion: the nominal posture with arms waving, knees bending and the root swaying (50 fps,
40 s), so every check does real work. Prints wall-clock rates and rates per CPU second (the
machine may be shared; CPU time is what one core spends). Run:

    python scripts/bench_check.py [--robot op3] [--frames 2000] [--repeat 3] [--old-model REV]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import subprocess
import time
import types
from pathlib import Path

import numpy as np

from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate import examples
from motion2robot.validate.api import kinematic_checks
from motion2robot.validate.context import prepare
from motion2robot.validate.dynamics import inverse_dynamics
from motion2robot.validate.options import CheckOptions
from motion2robot.validate.rollout import play


def bench_motion(robot, frames: int, fps: float = 50.0) -> RobotMotion:
    t = np.arange(frames) / fps
    q = np.tile(robot.nominal_qpos, (frames, 1))
    for name in robot.joint_names:
        j = robot.joint_index(name)
        span = robot.upper[j] - robot.lower[j]
        mid = np.clip(q[0, 7 + j], robot.lower[j] + 0.1 * span, robot.upper[j] - 0.1 * span)
        amp = 0.15 * span if ("sho" in name or "el" in name or "shoulder" in name or "elbow" in name) else 0.02 * span
        q[:, 7 + j] = mid + amp * np.sin(2 * np.pi * 0.4 * t + j)
    q[:, 0] += 0.01 * np.sin(2 * np.pi * 0.3 * t)
    return RobotMotion(q, fps, robot.joint_names, robot.name)


#: The commit before the friction-cone contact model (#19 item 1): its dynamics module is the old model.
OLD_MODEL = "f806171^"


def old_dynamics(rev: str) -> types.ModuleType | None:
    """``motion2robot/validate/dynamics.py`` as it was at ``rev`` (git), as a module; None without git."""
    root = Path(__file__).resolve().parents[1]
    try:
        src = subprocess.run(["git", "show", f"{rev}:motion2robot/validate/dynamics.py"], cwd=root,
                             capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    mod = types.ModuleType("old_dynamics")
    exec(compile(src, f"{rev}:dynamics.py", "exec"), mod.__dict__)  # noqa: S102 - the project's own history
    return mod


def best_cpu(fn, repeat: int) -> float:
    """Least CPU seconds of ``repeat`` calls of ``fn``."""
    out = np.inf
    for _ in range(repeat):
        c0 = time.process_time()
        fn()
        out = min(out, time.process_time() - c0)
    return out


def raised_lean(robot, opts: CheckOptions) -> list:
    """The issue's T1-like case on op3: double support, one sole 8 mm higher, the body leaning past its
    toes (``examples.slow_lean``) as (name, kinematics, support); empty for other robots."""
    if robot.name != "op3":
        return []
    ctx = prepare(examples.slow_lean(robot), robot, opts)
    corners = ctx.kin.corners.copy()
    corners[:, 1, :, 2] += 0.008
    return [("T1-like lean, one sole 8 mm higher", dataclasses.replace(ctx.kin, corners=corners),
             np.ones_like(ctx.support))]


def max_friction_ratio(forces: np.ndarray) -> float:
    """Peak |tangential| / normal force of one foot's summed corner forces (T, 2, 4, 3)."""
    foot = forces.sum(axis=2)
    tang, normal = np.linalg.norm(foot[..., :2], axis=-1), foot[..., 2]
    return float(np.max(np.where(normal > 1e-6, tang / np.maximum(normal, 1e-6), 0.0)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot", default="op3")
    ap.add_argument("--frames", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--playback-seconds", type=float, default=10.0)
    ap.add_argument("--old-model", default=OLD_MODEL, help="git revision whose dynamics.py is the old contact model")
    args = ap.parse_args()
    robot = load_robot(args.robot)
    motion = bench_motion(robot, args.frames)
    opts = CheckOptions()
    kinematic_checks(prepare(motion, robot, opts))  # warm-up: model compile, caches
    best: dict[str, float] = {}
    for _ in range(args.repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        ctx = prepare(motion, robot, opts)
        w1, _c1 = time.perf_counter(), time.process_time()
        kinematic_checks(ctx)
        w2, c2 = time.perf_counter(), time.process_time()
        for k, v in (("prepare", w1 - w0), ("checks", w2 - w1), ("total", w2 - w0), ("cpu", c2 - c0)):
            best[k] = min(best.get(k, np.inf), v)
    n = motion.num_frames
    print(f"robot {robot.name}: {n} frames; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"kinematic + balance + torque checks: {n / best['total']:,.0f} frames/s wall clock, "
          f"{n / best['cpu']:,.0f} frames/s of CPU time (per-frame pass + inverse dynamics "
          f"{best['prepare'] / n * 1e6:.1f} us/frame, checks {best['checks'] / n * 1e6:.1f} us/frame; best of {args.repeat})")
    ctx = prepare(motion, robot, opts)
    run_new = lambda: inverse_dynamics(ctx.kin, robot, ctx.support, servo_dynamics=opts.servo_dynamics)  # noqa: E731
    new = best_cpu(run_new, args.repeat)
    old_mod = old_dynamics(args.old_model)
    if old_mod is None:
        print(f"contact forces + torques: {new / n * 1e6:.1f} us/frame of CPU time (old model {args.old_model}: no git history)")
    else:
        old = best_cpu(lambda: old_mod.inverse_dynamics(ctx.kin, robot, ctx.support, servo_dynamics=opts.servo_dynamics),
                       args.repeat)
        print(f"contact forces + torques: {new / n * 1e6:.1f} us/frame of CPU time with friction cones and the CoP on "
              f"the soles, {old / n * 1e6:.1f} us/frame with the old model ({args.old_model}: friction unlimited), "
              f"same run; the whole check would run at {n / max(best['cpu'] - new + old, 1e-9):,.0f} frames/s of CPU "
              f"time with the old model ({n / best['cpu']:,.0f} with the new)")
        print("worth it: the old model's torques could rest on friction the floor cannot give, the new ones cannot:")
        for name, kin, support in (("bench motion", ctx.kin, ctx.support), *raised_lean(robot, opts)):
            o = old_mod.inverse_dynamics(kin, robot, support, servo_dynamics=opts.servo_dynamics)
            d = inverse_dynamics(kin, robot, support, servo_dynamics=opts.servo_dynamics)
            tang = np.linalg.norm(o.friction[..., :2], axis=-1)
            normal = o.normal.sum(axis=-1)
            ratio = np.where(normal > 1e-6, tang / np.maximum(normal, 1e-6), np.where(tang > 1e-6, np.inf, 0.0))
            print(f"  {name}: peak |torque| / limit {np.max(np.abs(o.tau) / robot.torque_limit):.2f} old, "
                  f"{np.max(np.abs(d.tau) / robot.torque_limit):.2f} new; peak friction / normal force of a foot "
                  f"{ratio.max():.2f} old, {max_friction_ratio(d.forces):.2f} new (mu {d.mu.max():.2f})")
    lean = examples.slow_lean(robot) if robot.name == "op3" else motion
    for name, mo in (("bench motion", motion), ("slow lean (ZMP leaves the feet)", lean)):
        dyn = prepare(mo, robot, opts).dyn
        print(f"contact forces, {name}: {dyn.supplied.mean():.0%} of frames supplied by friction-feasible forces, "
              f"{dyn.fallback.sum()} of {mo.num_frames} frames needed the library QP")
    short = RobotMotion(motion.qpos[: int(args.playback_seconds * motion.fps)], motion.fps, motion.joint_names, motion.robot)
    sctx = prepare(short, robot, opts)
    sim_s = short.duration + opts.settle_time
    c0 = time.process_time()
    pb = play(sctx)
    cpu = time.process_time() - c0
    print(f"physics playback: {pb.realtime_factor:.1f}x real time wall clock, {sim_s / cpu:.1f}x per CPU second "
          f"({sim_s:.1f} s simulated at {opts.timestep * 1000:g} ms steps, one thread; fell: {pb.fall_frame is not None})")


if __name__ == "__main__":
    main()

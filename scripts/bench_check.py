"""Benchmark of ``motion2robot check``: frames/s of the kinematic + balance + torque checks and the
physics playback's real-time factor, on a ~2,000-frame motion of the bundled OP3.

The motion: the nominal posture with arms waving, knees bending and the root swaying (50 fps,
40 s), so every check does real work. Prints wall-clock rates and rates per CPU second (the
machine may be shared; CPU time is what one core spends). Run:

    python scripts/bench_check.py [--robot op3] [--frames 2000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate import examples
from motion2robot.validate.api import kinematic_checks
from motion2robot.validate.context import prepare
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot", default="op3")
    ap.add_argument("--frames", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--playback-seconds", type=float, default=10.0)
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

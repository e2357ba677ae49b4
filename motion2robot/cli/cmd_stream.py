"""``motion2robot stream``: play a robot motion on Dynamixel servos (or a virtual chain).

    motion2robot stream MOTION.npz --virtual [--rate 100] [--loop --duration 10]
    motion2robot stream MOTION.npz --port /dev/ttyUSB0 --baud 2000000 [--calibration CAL.json]
    motion2robot stream MOTION.npz --dry-run
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from motion2robot.cli.numbers import RADIANS, RAD_PER_S, RATE_HZ, SECONDS, WATCHDOG_MS
from motion2robot.errors import UserError
from motion2robot.hardware.calibration import Calibration, load_calibration
from motion2robot.hardware.connect import (
    add_bus_options,
    open_bus_factory,
    target_from_args,
)
from motion2robot.hardware.dynamixel_bus import usb_latency_timer
from motion2robot.hardware.limits import JointLimits
from motion2robot.hardware.policy import TorquePolicy
from motion2robot.hardware.stream import joint_trajectory, stream_motion
from motion2robot.robot_motion import RobotMotion
from motion2robot.util.output import output_path

EXIT = {"end": 0, "interrupt": 130, "fault": 2, "refused": 2, "error": 3}


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "stream", help="stream a robot motion to Dynamixel servos (or a virtual chain) at a fixed rate",
        description="Ramp from the present pose to the first frame, play the motion at a fixed rate through the "
                    "safety guard (joint limits, velocity step per tick), ramp to the rest pose, then apply the "
                    "torque policy. Ctrl-C and faults stop the servos by the same policy; the port is always closed.")
    p.add_argument("motion", help="robot motion .npz (from 'motion2robot retarget')")
    add_bus_options(p, required=False)
    p.add_argument("--dry-run", action="store_true", help="no servos: run the guard and the timing loop only")
    p.add_argument("--rate", type=RATE_HZ, default=100.0, help="control rate in Hz, (0, 1000] (default 100)")
    p.add_argument("--loop", action="store_true", help="repeat the motion (stop with Ctrl-C or --duration)")
    p.add_argument("--duration", type=SECONDS, help="stop playing after this many seconds")
    p.add_argument("--robot", help="robot for limits and servo map (default: the motion's robot, else op3)")
    p.add_argument("--calibration", help="zero offsets file from 'motion2robot servos calibrate'")
    p.add_argument("--telemetry", help="telemetry JSONL path (default: MOTION.telemetry.jsonl beside the motion)")
    p.add_argument("--policy", help="torque policy: 'on_end=hold:2,on_fault=off,...' or a TOML file")
    p.add_argument("--on-end", help="at the end: 'off' or 'hold:SECONDS' (default hold:1)")
    p.add_argument("--on-interrupt", help="on Ctrl-C: 'off' (default) or 'hold:SECONDS'")
    p.add_argument("--on-fault", help="on a fault: 'off' (default) or 'hold:SECONDS'")
    p.add_argument("--watchdog-ms", type=WATCHDOG_MS,
                   help="Bus Watchdog in ms (20 ms steps, 0 = off; default: 100, or two control periods + 20 ms "
                        "when the rate is below 10 Hz; shorter than that is refused)")
    p.add_argument("--ramp-speed", type=RAD_PER_S, help="ramp-in/out speed in rad/s (default 0.5)")
    p.add_argument("--max-divergence", type=RADIANS,
                   help="present-vs-goal distance in rad that is a fault (default per joint: torque/kp compliance "
                        "+ two velocity steps + 2 ticks; see docs/hardware.md)")
    p.add_argument("--rest", choices=["nominal", "last"], default="nominal",
                   help="after the motion: ramp to the robot's nominal posture (default) or stay at the last frame")
    p.add_argument("--realtime", action="store_true", help="run the loop under SCHED_FIFO when permitted (root)")
    p.add_argument("--sag-compensation", action="store_true",
                   help="raise every goal by the sag its servo will have under the motion's own torques "
                        "(tau/kp from inverse dynamics), as 'check --sag-compensation' plays it")
    p.set_defaults(func=run)


def policy_from_args(args: argparse.Namespace) -> TorquePolicy:
    pol = TorquePolicy.parse(args.policy) if args.policy else TorquePolicy()
    items = {k: v for k, v in (("on_end", args.on_end), ("on_interrupt", args.on_interrupt), ("on_fault", args.on_fault),
                               ("watchdog_ms", args.watchdog_ms), ("ramp_speed", args.ramp_speed)) if v is not None}
    return TorquePolicy.from_mapping(items, pol) if items else pol


def run(args: argparse.Namespace) -> int:
    from motion2robot.robot import load_robot

    if not (args.virtual or args.port or args.dry_run):
        raise UserError("stream: say where the servos are: --virtual, --port DEV, or --dry-run")
    motion = RobotMotion.load(args.motion)
    robot = load_robot(args.robot or motion.robot or "op3")
    servo_map = robot.config.servos
    if servo_map is None:
        raise UserError(f"robot '{args.robot or motion.robot}' has no [servos] section in its config; add one to stream")
    policy = policy_from_args(args)
    if not args.dry_run:
        policy, note = policy.for_rate(args.rate)  # refuse a watchdog the rate cannot feed, before anything
        if note:
            print(f"note: {note}", file=sys.stderr)
    offsets = load_calibration(args.calibration) if args.calibration else None
    cal = Calibration.from_servo_map(servo_map, offsets)
    joint_trajectory(motion, cal.joints)  # fail early on a motion for another robot
    if args.sag_compensation:
        from motion2robot.validate.sag import compensated_motion

        motion = compensated_motion(motion, robot)
        print(f"sag compensation: goals raised by up to {motion.meta['sag_compensation']:.3f} rad", flush=True)
    hinge = {n: i for i, n in enumerate(robot.joint_names)}
    rest = None if args.rest == "last" else np.array([robot.nominal_qpos[7 + hinge[j]] for j in cal.joints])
    telemetry = str(output_path(args.telemetry or str(Path(args.motion).with_suffix("")) + ".telemetry.jsonl",
                                "telemetry", ".jsonl"))
    limits = JointLimits.from_robot(robot)
    if args.dry_run:
        report = stream_motion(motion, limits, servo_map, None, rate_hz=args.rate, loop=args.loop, dry_run=True,
                               telemetry_path=telemetry, policy=policy, offsets=offsets, rest_pose=rest,
                               max_seconds=args.duration, realtime=args.realtime,
                               max_divergence=args.max_divergence)
    else:
        target = target_from_args(args, servo_map)
        if target.port:
            lt = usb_latency_timer(target.port)
            if lt is not None and lt > target.latency_ms:
                print(f"warning: {target.port} USB latency timer is {lt} ms; set it to 1 ms "
                      "(see docs/hardware.md) or reads will be slow", file=sys.stderr)
        print(f"streaming {args.motion} ({motion.num_frames} frames at {motion.fps:g} fps) to {target.describe()} "
              f"at {args.rate:g} Hz; {policy.describe()}", flush=True)
        with open_bus_factory(target, servo_map) as factory:
            report = stream_motion(motion, limits, servo_map, factory, rate_hz=args.rate, loop=args.loop,
                                   telemetry_path=telemetry, policy=policy, offsets=offsets, rest_pose=rest,
                                   max_seconds=args.duration, realtime=args.realtime,
                                   max_divergence=args.max_divergence)
    print(report.describe())
    if report.torque_after:
        print("torque: " + " ".join(f"{i}:{'on' if v else ('off' if v is False else '?')}"
                                    for i, v in report.torque_after.items()))
    for f in report.faults:
        print(f"motion2robot: error: stream fault ({report.fault_kind}): {f}", file=sys.stderr)
    if report.stop_reason == "fault" and not report.faults:
        print(f"motion2robot: error: stream fault ({report.fault_kind}): torque-off failed: "
              f"{'; '.join(report.torque_off_errors)}", file=sys.stderr)
    if report.stop_reason == "interrupt":
        print("motion2robot: interrupted; servos stopped by the torque policy", file=sys.stderr)
    return EXIT.get(report.stop_reason, 3)

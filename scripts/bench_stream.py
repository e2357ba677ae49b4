"""Benchmark the streaming loop against the virtual chain with wire-time emulation.

20 XM430-W350 servos (the OP3 servo map), Return Delay Time 0, fast sync read; per tick one
sync write of goal positions and one fast sync read of present positions through DynamixelBus
and the real dynamixel-sdk. Prints the loop figures, the bytes per tick counted by the chain and
the wire limit they imply (10 bits per byte), at 1 Mbps for --seconds (default 60) at --rate
(default 100 Hz), then the highest rate reached at 4 Mbps (sweep, --sweep-seconds each) with no
overrun and p99 jitter <= 1 ms.

    python scripts/bench_stream.py [--seconds 60] [--rate 100] [--realtime] [--sweep 200,300,...]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile

import numpy as np

from motion2robot.hardware.calibration import Calibration
from motion2robot.hardware.dynamixel_bus import DynamixelBus
from motion2robot.hardware.limits import JointLimits
from motion2robot.hardware.policy import TorquePolicy
from motion2robot.hardware.stream import stream_motion
from motion2robot.hardware.virtual_chain import PTY_LATENCY_MS, VirtualChain
from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion


def demo_motion(robot, seconds: float = 4.0, fps: float = 50.0) -> RobotMotion:
    t = np.arange(int(seconds * fps)) / fps
    qpos = np.tile(robot.nominal_qpos, (t.size, 1))
    qpos[:, 7:] += 0.25 * np.sin(2 * np.pi * 0.5 * t)[:, None]
    return RobotMotion(qpos, fps, robot.joint_names, "op3")


def run(robot, baud: int, rate: float, seconds: float, realtime: bool, latency_ms: float = PTY_LATENCY_MS) -> tuple:
    sm = robot.config.servos
    cal = Calibration.from_servo_map(sm)
    m = demo_motion(robot)
    hinge = {n: i for i, n in enumerate(robot.joint_names)}
    first = np.array([m.joints[0, hinge[j]] for j in cal.joints])
    positions = dict(zip(cal.ids.tolist(), cal.to_ticks(first).tolist()))
    names = dict(zip(cal.ids.tolist(), cal.joints))
    with tempfile.TemporaryDirectory() as tmp, \
            VirtualChain(cal.ids.tolist(), baud=baud, wire_time=True, return_delay_time=0, positions=positions) as chain:
        rep = stream_motion(m, JointLimits.from_robot(robot), sm,
                            lambda: DynamixelBus(chain.port_name, baud, sm.model, names=names,
                                                 latency_timer_ms=latency_ms),
                            rate_hz=rate, loop=True, max_seconds=seconds, realtime=realtime,
                            telemetry_path=os.path.join(tmp, "t.jsonl"),
                            policy=TorquePolicy(on_end=0.0, ramp_out=False))
        stats = chain.stats()
    return rep, stats


def wire(stats: dict, ticks: int, baud: int) -> str:
    per_tick = (stats["rx_bytes"] + stats["tx_bytes"]) / max(ticks, 1)
    wire_s = per_tick * 10.0 / baud
    return (f"{per_tick:.1f} bytes/tick on the wire ({stats['rx_bytes']} to servos, {stats['tx_bytes']} from servos "
            f"incl. start/stop) = {wire_s * 1e3:.3f} ms/tick -> wire limit {1.0 / wire_s:.0f} Hz at {baud} baud")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--rate", type=float, default=100.0)
    ap.add_argument("--realtime", action="store_true", help="SCHED_FIFO for the host loop (root)")
    ap.add_argument("--sweep", default="200,300,400,500,600,800", help="rates (Hz) to try at 4 Mbps")
    ap.add_argument("--sweep-seconds", type=float, default=5.0)
    ap.add_argument("--latency-ms", type=float, default=PTY_LATENCY_MS,
                    help="latency the SDK reply timeouts assume (default: the pty relay's, PTY_LATENCY_MS)")
    args = ap.parse_args()
    robot = load_robot("op3")
    print(f"python {sys.version.split()[0]}, {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}; "
          f"host loop realtime requested: {args.realtime}; virtual chain under SCHED_FIFO when permitted; "
          f"SDK timeouts assume {args.latency_ms:g} ms pty latency")
    rep, stats = run(robot, 1_000_000, args.rate, args.seconds, args.realtime, args.latency_ms)
    print(f"\n1 Mbps, 20 servos, RDT 0, {args.rate:g} Hz for {args.seconds:g} s: stop={rep.stop_reason} "
          f"faults={len(rep.faults)} recovered={rep.recovered}")
    for f in rep.faults:
        print(f"  fault: {f}")
    print("  " + rep.figures.describe())
    print("  " + wire(stats, rep.ticks, 1_000_000))
    ok = rep.figures.overruns == 0 and rep.figures.jitter_p99_ms <= 1.0 and rep.figures.achieved_hz >= 0.99 * args.rate
    print(f"  acceptance (>= 100 Hz, p99 jitter <= 1 ms, no overruns): {'PASS' if ok else 'FAIL'}")
    best_clean = best_jitter = None
    print(f"\n4 Mbps sweep ({args.sweep_seconds:g} s each):")
    for r in [float(x) for x in args.sweep.split(",") if x]:
        rep4, stats4 = run(robot, 4_000_000, r, args.sweep_seconds, args.realtime, args.latency_ms)
        f = rep4.figures
        ended = rep4.stop_reason == "end"
        print(f"  {r:5.0f} Hz: {f.describe()}; stop={rep4.stop_reason}")
        if r == float(args.sweep.split(",")[0]):
            print("         " + wire(stats4, rep4.ticks, 4_000_000))
        if ended and f.jitter_p99_ms <= 1.0 and f.achieved_hz >= 0.99 * r:
            best_jitter = r
            if f.overruns == 0:
                best_clean = r
    print(f"\nat 4 Mbps: highest rate with p99 jitter <= 1 ms and >= 99% of the target rate: {best_jitter or 'none'} Hz; "
          f"with also no overrun: {best_clean or 'none'} Hz")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

"""Does servo sag compensation help? The physics rollout of ``check`` over every readable clip,
with and without ``sag_compensation``, on the same retargeted motions.

Each clip is read, retargeted with the default options, then played twice by the rollout (the
servos fed stream's goals at the stream rate; once with the planned angles, once with the
planned angles plus tau/kp). Prints, per setting: clips that stay up, the mean and median of the
per-clip tracking RMS (simulated minus planned joint angle, mean over joints, frames before any
fall; a clip that falls before its first frame counts 0, so compare the clips that stay up both
ways, printed on their own), and the clips whose outcome changes. Run:

    python scripts/bench_sag.py [/work/shared/motions] [--robot op3] [--rate 100] [--limit N]
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace

import numpy as np

from motion2robot.batch.work import expand_inputs
from motion2robot.motion import read_motion
from motion2robot.retarget import retarget
from motion2robot.robot import load_robot
from motion2robot.validate.context import prepare
from motion2robot.validate.options import CheckOptions
from motion2robot.validate.rollout import play, rollout


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("inputs", nargs="*", default=["../shared/motions"])
    ap.add_argument("--robot", default="op3")
    ap.add_argument("--rate", type=float, default=100.0, help="stream rate of the servo goals (Hz)")
    ap.add_argument("--limit", type=int, help="only the first N clips")
    args = ap.parse_args()
    robot = load_robot(args.robot)
    items = expand_inputs(args.inputs).items[: args.limit]
    base = CheckOptions(stream_rate=args.rate)
    rows, skipped = [], 0
    t0 = time.process_time()
    for item in items:
        try:
            human = read_motion(item.path, clip=item.clip)[0]
            motion = retarget(human, robot)
        except Exception as err:  # unreadable clips are counted, not measured
            skipped += 1
            print(f"skip {item.key}: {str(err).splitlines()[0][:100]}")
            continue
        if motion.num_frames < 2:
            skipped += 1
            continue
        ctx = prepare(motion, robot, base)
        out = {}
        for on in (False, True):
            c = replace(ctx, options=replace(base, sag_compensation=on))
            r = rollout(c, play(c))
            out[on] = (not r["fell"], r["tracking_rms_mean_rad"])
        rows.append((item.key, out))
        print(f"{item.key[-60:]:60s} off: {'up  ' if out[False][0] else 'fell'} {out[False][1]:.4f} rad   "
              f"on: {'up  ' if out[True][0] else 'fell'} {out[True][1]:.4f} rad", flush=True)
    n = len(rows)
    print(f"\nrobot {robot.name}, {n} clips played ({skipped} unreadable or unsolved skipped), goals at {args.rate:g} Hz; "
          f"{time.process_time() - t0:.0f} CPU s; load average {os.getloadavg()[0]:.1f}")
    for on, name in ((False, "without sag compensation"), (True, "with sag compensation   ")):
        up = sum(r[1][on][0] for r in rows)
        rms = np.array([r[1][on][1] for r in rows])
        print(f"{name}: stays up {up}/{n} ({100 * up / max(n, 1):.0f} %), tracking RMS mean {rms.mean():.4f} rad, "
              f"median {np.median(rms):.4f} rad")
    both = [r for r in rows if r[1][False][0] and r[1][True][0]]
    if both:
        off = np.array([r[1][False][1] for r in both])
        on = np.array([r[1][True][1] for r in both])
        print(f"clips up both ways ({len(both)}): tracking RMS mean {off.mean():.4f} -> {on.mean():.4f} rad, "
              f"median {np.median(off):.4f} -> {np.median(on):.4f} rad; better on {(on < off).sum()}, "
              f"worse on {(on > off).sum()}")
    saved = [r[0] for r in rows if r[1][True][0] and not r[1][False][0]]
    lost = [r[0] for r in rows if r[1][False][0] and not r[1][True][0]]
    print(f"stays up only with compensation: {len(saved)} {saved[:5]}")
    print(f"stays up only without: {len(lost)} {lost[:5]}")


if __name__ == "__main__":
    main()

#!/usr/bin/env python
"""Benchmark ``motion2robot batch``: clips/s and frames/s for retarget + kinematic checks.

Builds a small corpus with scripts/make_corpus.py (default 60 clips of ~150 frames), runs the
local backend (default 2 workers, --no-physics) through the same code as the CLI, and prints:
start-up time (spawn + robot load + casadi compile per worker), steady-state clips/s and frames/s,
the projected wall time for 10,000 clips (target <= 15 min), mean seconds per clip per stage, and
the peak resident memory of each worker after its first, ..., last clip (to show it stays flat).

    python scripts/bench_batch.py [--clips 60] [--jobs 2] [--robot op3] [--physics]
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from make_corpus import make_corpus  # noqa: E402

from motion2robot.batch import BatchConfig, plan_batch, run_plan, summarize  # noqa: E402

TARGET_CLIPS = 10_000
TARGET_MINUTES = 15.0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--clips", type=int, default=60)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--robot", default="op3")
    ap.add_argument("--physics", action="store_true", help="include the MuJoCo rollout")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args(argv)

    with tempfile.TemporaryDirectory(prefix="m2r_bench_") as tmp:
        corpus = Path(tmp) / "corpus"
        make_corpus(corpus, a.clips, a.seed)
        out = Path(tmp) / "results.jsonl"
        plan = plan_batch([corpus], out)
        config = BatchConfig(robot=a.robot, physics=a.physics)
        stamps: list[float] = []
        rows: list[dict] = []
        t0 = time.perf_counter()

        def on_row(row: dict) -> None:
            stamps.append(time.perf_counter() - t0)
            rows.append(row)

        run_plan(plan, config, backend="local", jobs=a.jobs, on_row=on_row)
        wall = time.perf_counter() - t0

    s = summarize(rows)
    ok = [r for r in rows if not r["error"]]
    frames = sum(r["frames"] or 0 for r in rows)
    span = stamps[-1] - stamps[0]
    steady = (len(stamps) - 1) / span if span > 0 else float("nan")
    frames_per_clip = frames / max(1, len(rows))
    projected = stamps[0] + TARGET_CLIPS / steady
    mean = {k: sum((r["timings"][k] or 0) for r in ok) / max(1, len(ok))
            for k in ("read_s", "retarget_s", "check_s", "total_s", "cpu_s")}
    workers: dict[int, list[float]] = {}
    for r in rows:
        workers.setdefault(r["worker"]["pid"], []).append(r["worker"]["max_rss_mb"])
    driver_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

    mode = "retarget + all checks incl. physics rollout" if a.physics else "retarget + kinematic checks (--no-physics)"
    print(f"bench_batch: {len(rows)} clips, {frames} frames ({frames_per_clip:.1f}/clip), robot {a.robot}, "
          f"{a.jobs} workers, {mode}")
    print(f"  errors: {s.errors}; executable: {s.feasible}; not executable: {s.infeasible}")
    if s.error_kinds:
        print(f"  first error: {s.error_kinds[0][2]}")
    print(f"  wall {wall:.2f} s; first row after {stamps[0]:.2f} s (spawn + robot load + compile)")
    print(f"  steady state: {steady:.2f} clips/s, {steady * frames_per_clip:.1f} frames/s")
    print(f"  overall:      {len(rows) / wall:.2f} clips/s, {frames / wall:.1f} frames/s")
    print(f"  per clip in a worker (mean s): read {mean['read_s']:.4f}, retarget {mean['retarget_s']:.4f}, "
          f"check {mean['check_s']:.4f}, total {mean['total_s']:.4f}")
    verdict = "meets" if projected <= TARGET_MINUTES * 60 else "MISSES"
    print(f"  projected for {TARGET_CLIPS} clips: {projected / 60:.1f} min at the measured rate "
          f"({verdict} the <= {TARGET_MINUTES:.0f} min target)")
    cpu_projected = stamps[0] + TARGET_CLIPS * mean["cpu_s"] / a.jobs
    verdict = "meets" if cpu_projected <= TARGET_MINUTES * 60 else "MISSES"
    print(f"  CPU per clip {mean['cpu_s']:.4f} s vs wall {mean['total_s']:.4f} s (cores shared with other work when "
          f"they differ): with {a.jobs} free cores {cpu_projected / 60:.1f} min ({verdict} the target)")
    print(f"  load average during the run: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    for pid, mb in sorted(workers.items()):
        marks = sorted({0, len(mb) // 4, len(mb) // 2, 3 * len(mb) // 4, len(mb) - 1})
        trail = ", ".join(f"{mb[i]:.0f} MB after clip {i + 1}" for i in marks)
        print(f"  worker {pid}: {len(mb)} clips; peak RSS {trail}")
    print(f"  driver peak RSS {driver_mb:.0f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Throughput of scoring: samples of 196 frames scored per minute, with and without the physics
rollout, the per-sample overhead of the in-process API vs the CLI, and where the time goes.

    python scripts/bench_score.py [--samples 64] [--jobs 2] [--profile]

Samples: the real clips of ../shared/motions with at least 196 frames at 20 fps (MDM's 196-frame
"throw a ball" samples, two HumanML3D clips), cut to 196 frames and repeated up to ``--samples``
(64 by default: a rate per minute is a sustained rate, and on a few samples the last worker's
unfinished clip, up to 0.3 s, weighs on the wall-clock figure).
Figures per mode: wall-clock samples/min of a warm worker pool (the pool is started and the
compiled problems loaded by a first call, not timed), and the CPU-time figure (60 / mean worker
CPU seconds per sample x jobs), which is what the machine could do if the cores were not shared.
The CLI is timed end to end (process start, imports, workers, reading the file, writing the
results) on the same samples saved as one .npy file, on 1 sample and on all of them, in CPU seconds
of the process and its workers (wall time on a shared machine is mostly other people's work): the
slope is its cost per sample, the rest its fixed cost per call; the in-process figure is the
driver's CPU time plus the workers' CPU time for the samples. ``--profile`` runs one sample in this process
under cProfile and prints the cumulative time of the pipeline's stages.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

FRAMES = 196
MOTIONS = Path(__file__).resolve().parents[2] / "shared" / "motions"


def samples(n: int) -> np.ndarray:
    """(n, 196, 22, 3) HumanML3D joints (y up) from the shared clips."""
    from motion2robot.motion.safe_pickle import load_npy

    res = load_npy(MOTIONS / "mdm_results/mdm_throw_ball_results.npy")
    res = res.item() if isinstance(res, np.ndarray) else res
    pool = [res["motion"][i].transpose(2, 0, 1)[:FRAMES] for i, length in enumerate(res["lengths"]) if length >= FRAMES]
    pool += [np.load(MOTIONS / f"humanml3d_joints/{c}.npy")[:FRAMES] for c in ("007005", "011673")]
    return np.stack([pool[i % len(pool)] for i in range(n)]).astype(np.float32)


def api_run(batch: np.ndarray, physics: bool, jobs: int) -> dict:
    from motion2robot import api

    api.retarget_many(batch[:jobs], physics=physics, jobs=jobs)  # warm: start the pool, load the problems
    t0, c0 = time.perf_counter(), time.process_time()
    res = api.score(batch, physics=physics, jobs=jobs)
    wall, driver = time.perf_counter() - t0, time.process_time() - c0
    cpu = [s.record["timings"]["cpu_s"] for s in res.samples if s.record["timings"]["cpu_s"] is not None]
    attempts = [len(s.motion.meta.get("attempts", [])) for s in res.samples if s.motion is not None]
    return {"wall_s": wall, "per_min_wall": 60 * len(batch) / wall, "cpu_s": float(np.mean(cpu)),
            "total_cpu_s": driver + float(np.sum(cpu)),
            "per_min_cpu": 60 * jobs / float(np.mean(cpu)), "attempts": float(np.mean(attempts)),
            "executable": res.figures.executable, "errors": res.figures.errors}


def cli_run(batch: np.ndarray, physics: bool, jobs: int) -> dict:
    """Wall time and CPU time (the CLI process and its workers) of ``motion2robot score`` on
    ``batch`` saved as one file."""
    with tempfile.TemporaryDirectory() as tmp:
        np.save(Path(tmp) / "b.npy", batch)
        cmd = [sys.executable, "-m", "motion2robot", "score", str(Path(tmp) / "b.npy"), "--out", str(Path(tmp) / "o"),
               "-q", "-j", str(jobs)] + ([] if physics else ["--no-physics"])
        t0, r0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run(cmd, capture_output=True, text=True, check=True)
        wall, r1 = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
        figs = json.loads((Path(tmp) / "o" / "score.json").read_text())["sets"][0]
    cpu = (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu, "executable": figs["executable"]}


def profile_one(batch: np.ndarray, physics: bool) -> None:
    from motion2robot import api

    api.retarget_many(batch[:1], physics=physics, jobs=0)  # compile/load outside the profile
    prof = cProfile.Profile()
    prof.enable()
    api.retarget_many(batch[1:2], physics=physics, jobs=0)
    prof.disable()
    st = pstats.Stats(prof)
    total = max(v[3] for v in st.stats.values())
    stages = {"whole_body": "whole-body solves (all attempts)", "check": "checks (all attempts)",
              "compute_kinematics": "  of which per-frame MuJoCo pass", "inverse_dynamics": "  of which inverse dynamics",
              "kinematic_checks": "  of which the kinematic checks", "play": "  of which physics playback",
              "fidelity": "fidelity figures", "to_clips": "tensor -> clips"}
    found: dict[str, float] = {}
    for (file, _, fn), v in st.stats.items():
        if fn in stages and "motion2robot" in file:
            found[fn] = found.get(fn, 0.0) + v[3]
    print(f"  profile of one sample ({'with' if physics else 'without'} rollout), {total:.2f} s in total:")
    for fn, label in stages.items():
        if fn in found:
            print(f"    {label:<38} {found[fn]:6.2f} s  ({100 * found[fn] / total:4.1f}%)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--samples", type=int, default=64)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--profile", action="store_true")
    args = ap.parse_args()
    batch = samples(args.samples)
    print(f"{len(batch)} samples of {FRAMES} frames (20 fps), {args.jobs} workers")
    from motion2robot import api

    try:
        for physics in (False, True):
            mode = "with rollout" if physics else "without rollout"
            a = api_run(batch, physics, args.jobs)
            api.close()
            one, full = cli_run(batch[:1], physics, args.jobs), cli_run(batch, physics, args.jobs)
            print(f"{mode}: API {a['per_min_wall']:.1f} samples/min wall ({a['wall_s']:.1f} s), "
                  f"{a['per_min_cpu']:.1f} samples/min by CPU time ({a['cpu_s']:.2f} CPU s per sample, "
                  f"{a['attempts']:.1f} retarget attempts per sample; {a['executable']} executable, {a['errors']} errors)")
            n = len(batch)
            slope = (full["cpu_s"] - one["cpu_s"]) / (n - 1)
            fixed = one["cpu_s"] - slope
            api_each = a["total_cpu_s"] / n
            print(f"  CLI end to end, CPU time of the process and its workers: {one['cpu_s']:.1f} s for 1 sample, "
                  f"{full['cpu_s']:.1f} s for {n} (wall {one['wall_s']:.1f} s and {full['wall_s']:.1f} s): "
                  f"{slope:.2f} s per sample + {fixed:.1f} s per call (process start, imports, {args.jobs} workers "
                  f"started, problems loaded); warm in-process API: {api_each:.2f} CPU s per sample (driver + "
                  f"workers): overhead of the CLI {slope - api_each:+.2f} s per sample and {fixed:.1f} s per call "
                  f"({full['executable']} executable)")
            if args.profile:
                profile_one(batch, physics)
    finally:
        api.close()

if __name__ == "__main__":
    main()

#!/usr/bin/env python
"""Build a synthetic corpus of HumanML3D joint clips for batch benchmarks and tests.

Sources: the HumanML3D joint files and MDM results (model outputs) in ../shared/motions
(``humanml3d_joints/*.npy``, ``mdm_results/*.npy``: the first 22 SMPL joints, y up, metres, 20 fps).
Each output clip is one source clip with
- a time-warp (playback speed 0.8-1.25, linear interpolation; slowed down further, to at most
  2x, when the source is too short for the window),
- a crop to a window of about 150 frames (130-170; shorter when even 2x cannot fill it),
- a left/right mirror with probability 1/2 (x -> -x, left and right joints swapped),
- small perturbations: body scale 0.95-1.05 and a smooth per-joint offset (1 cm standard deviation,
  knots every 10 frames),
then put back in the HumanML3D frame: floor (lowest foot joint of the clip) at y = 0, root at
x = z = 0 on frame 0. Written as float32 (T, 22, 3) ``clip_00000.npy`` ... plus ``corpus.csv``
(file, source, clip, speed, mirrored, start, frames). Deterministic for a given ``--seed``.

    python scripts/make_corpus.py --n 10000 --out /tmp/corpus
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve()
#: SMPL22 left/right pairs (hip, knee, ankle, foot, collar, shoulder, elbow, wrist).
LR_PAIRS = ((1, 2), (4, 5), (7, 8), (10, 11), (13, 14), (16, 17), (18, 19), (20, 21))
FEET = (7, 8, 10, 11)
MIRROR_ORDER = np.arange(22)
for _a, _b in LR_PAIRS:
    MIRROR_ORDER[_a], MIRROR_ORDER[_b] = _b, _a


def shared_motions() -> Path:
    import os

    env = os.environ.get("MOTION2ROBOT_SHARED")
    return (Path(env) if env else HERE.parents[2] / "shared") / "motions"


def load_sources(motions: Path) -> list[tuple[str, np.ndarray]]:
    """(name, (T, 22, 3) float64 y-up joints) of every HumanML3D-space clip in ``motions``."""
    from motion2robot.motion.safe_pickle import load_npy

    out: list[tuple[str, np.ndarray]] = []
    for f in sorted((motions / "humanml3d_joints").glob("*.npy")):
        arr = np.load(f, allow_pickle=False)
        if arr.ndim == 3 and arr.shape[2] == 3 and arr.shape[1] >= 22:
            out.append((f"humanml3d_joints/{f.name}", arr[:, :22].astype(np.float64)))
    for f in sorted((motions / "mdm_results").glob("*.npy")):
        obj = load_npy(f)
        if isinstance(obj, np.ndarray) and obj.dtype.hasobject and obj.shape == ():
            obj = obj.item()
        if isinstance(obj, dict):
            motion = np.asarray(obj["motion"])
            lengths = np.asarray(obj.get("lengths", np.full(len(motion), motion.shape[-1]))).reshape(-1)
        else:
            motion, lengths = np.asarray(obj), np.full(len(obj), obj.shape[-1])
        if motion.ndim != 4 or motion.shape[1:3] != (22, 3):
            continue
        for i, (m, n) in enumerate(zip(motion, lengths, strict=True)):
            out.append((f"mdm_results/{f.name}#{i}", np.transpose(m[:, :, : int(n)], (2, 0, 1)).astype(np.float64)))
    if not out:
        raise SystemExit(f"no HumanML3D joint clips found under {motions}")
    return out


def time_warp(x: np.ndarray, speed: float) -> np.ndarray:
    """Resample (T, ...) frames at ``speed`` source frames per output frame (linear)."""
    t = np.arange(0.0, len(x) - 1 + 1e-9, speed)
    i = np.minimum(np.floor(t).astype(int), len(x) - 2)
    w = (t - i).reshape(-1, *([1] * (x.ndim - 1)))
    return x[i] * (1 - w) + x[i + 1] * w


def smooth_noise(rng: np.random.Generator, frames: int, sigma: float, every: int = 10) -> np.ndarray:
    """(frames, 22, 3) offsets: Gaussian knots every ``every`` frames, linearly interpolated."""
    knots = rng.normal(0.0, sigma, size=(frames // every + 2, 22, 3))
    return time_warp(knots, 1.0 / every)[:frames]


def to_humanml3d_frame(x: np.ndarray) -> np.ndarray:
    x = x - np.array([x[0, 0, 0], 0.0, x[0, 0, 2]])
    x[..., 1] -= x[:, FEET, 1].min()
    return x


def make_clip(src: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, dict]:
    window = int(rng.integers(130, 171))
    speed = float(rng.uniform(0.8, 1.25))
    speed = max(0.5, min(speed, (len(src) - 1) / (window - 1)))
    warped = time_warp(src, speed)
    window = min(window, len(warped))
    start = int(rng.integers(0, len(warped) - window + 1))
    x = warped[start:start + window].copy()
    mirrored = bool(rng.random() < 0.5)
    if mirrored:
        x = x[:, MIRROR_ORDER] * np.array([-1.0, 1.0, 1.0])
    root = x[:, :1]
    x = root + (x - root) * rng.uniform(0.95, 1.05) + smooth_noise(rng, len(x), 0.01)
    return to_humanml3d_frame(x).astype(np.float32), {
        "speed": round(speed, 4), "mirrored": mirrored, "start": start, "frames": len(x)}


def make_corpus(out: Path, n: int, seed: int = 0, motions: Path | None = None) -> list[Path]:
    """Write ``n`` clips to ``out``; returns their paths."""
    sources = load_sources(motions or shared_motions())
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    paths = []
    with open(out / "corpus.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["file", "source", "speed", "mirrored", "start", "frames"])
        for k in range(n):
            name, src = sources[int(rng.integers(len(sources)))]
            clip, info = make_clip(src, rng)
            path = out / f"clip_{k:05d}.npy"
            np.save(path, clip)
            paths.append(path)
            w.writerow([path.name, name, info["speed"], int(info["mirrored"]), info["start"], info["frames"]])
    return paths


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=10_000, help="number of clips (default 10000)")
    ap.add_argument("--out", type=Path, required=True, help="output folder")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--motions", type=Path, help="source folder (default ../shared/motions)")
    a = ap.parse_args(argv)
    paths = make_corpus(a.out, a.n, a.seed, a.motions)
    frames = sum(np.load(p, mmap_mode="r").shape[0] for p in paths)
    print(f"wrote {len(paths)} clips, {frames} frames ({frames / max(1, len(paths)):.1f} per clip) to {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

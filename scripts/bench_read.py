"""Reader throughput: 263-d feature decoding (frames/s) and reading 1,000 joint files vs np.load.

Run: python scripts/bench_read.py [--clips 1000] [--frames 196] [--files 1000]
Prints its figures; nothing is asserted.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from motion2robot.motion.features import decode_positions
from motion2robot.motion.read import read_motion


def _best(fn, repeat: int = 3) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _synthetic_features(n: int, t: int, rng: np.random.Generator) -> np.ndarray:
    f = rng.normal(0.0, 0.1, size=(n, t, 263))
    f[..., 3] = 0.9
    return f.astype(np.float32)  # the data sets and models store float32


def _walk(t: int, rng: np.random.Generator) -> np.ndarray:
    rest = np.array([[0, .95, 0], [.06, .86, 0], [-.06, .86, 0], [0, 1.06, 0], [.1, .48, 0], [-.1, .48, 0],
                     [0, 1.19, 0], [.1, .08, 0], [-.1, .08, 0], [0, 1.25, 0], [.1, .02, .12], [-.1, .02, .12],
                     [0, 1.46, 0], [.07, 1.38, 0], [-.07, 1.38, 0], [0, 1.55, .03], [.17, 1.4, 0], [-.17, 1.4, 0],
                     [.42, 1.4, 0], [-.42, 1.4, 0], [.66, 1.4, 0], [-.66, 1.4, 0]])
    pos = np.repeat(rest[None], t, axis=0) + rng.normal(0, 0.005, size=(t, 22, 3))
    pos[..., 2] += np.arange(t)[:, None] * 0.05
    return pos.astype(np.float32)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--clips", type=int, default=1000)
    ap.add_argument("--frames", type=int, default=196)
    ap.add_argument("--files", type=int, default=1000)
    a = ap.parse_args()
    rng = np.random.default_rng(0)

    feats = _synthetic_features(a.clips, a.frames, rng)
    total = a.clips * a.frames
    t_batch = _best(lambda: decode_positions(feats))
    t_clip = _best(lambda: [decode_positions(f) for f in feats])
    print(f"263-d decode, batched ({a.clips} clips x {a.frames} frames): {total / t_batch:,.0f} frames/s "
          f"({t_batch * 1e3:.1f} ms)")
    print(f"263-d decode, one call per clip:                    {total / t_clip:,.0f} frames/s "
          f"({t_clip * 1e3:.1f} ms)")

    shared = Path(__file__).resolve().parents[2] / "shared" / "motions" / "humanml3d_vecs" / "012314.npy"
    if shared.is_file():
        t_read = _best(lambda: read_motion(shared), repeat=5)
        print(f"read_motion of a real 263-d clip (170 frames, decode + canonical frame): {t_read * 1e3:.2f} ms")

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for i in range(a.files):
            np.save(folder / f"{i:06d}.npy", _walk(int(rng.integers(40, 197)), rng))
        files = sorted(folder.glob("*.npy"))
        t_np = _best(lambda: [np.load(f) for f in files])
        t_one = _best(lambda: [read_motion(f) for f in files])
        t_dir = _best(lambda: read_motion(folder))
        print(f"{a.files} HumanML3D joint files: np.load {t_np:.3f} s; read_motion per file {t_one:.3f} s "
              f"({t_one / a.files * 1e3:.2f} ms/file); read_motion(folder) {t_dir:.3f} s; "
              f"overhead vs np.load x{t_one / t_np:.1f}")


if __name__ == "__main__":
    main()

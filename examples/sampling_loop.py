"""A sampling loop that keeps its sample executable by the robot: ``project`` every k steps.

A diffusion-style sampler refines a motion over many steps; physically guided samplers replace
the intermediate sample by its projection onto what is possible. Here the projection is the
robot's: ``motion2robot.projection.project`` retargets the sample onto the robot (executable
retargeting, tempo and legs judged by the full check) and maps the robot's motion back onto the
human skeleton, in the sample's own layout ((T, 22, 3) HumanML3D joints, y up, metres, 20 fps).

No model weights are available here, so the denoiser is a stand-in: any callable
``denoise(x, step) -> x`` works. The stand-in pulls a noisy sample towards a real clip, smooths it
in time and adds noise that shrinks with the steps, as a sampler's trajectory does.

Run (from the repository root):
    python examples/sampling_loop.py                       # the bundled demo motion
    python examples/sampling_loop.py ../shared/motions/humanml3d_joints/012314.npy --steps 30 --every 10
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from importlib import resources
from pathlib import Path

import numpy as np

from motion2robot.projection import project
from motion2robot.robot import load_robot

Denoiser = Callable[[np.ndarray, int], np.ndarray]


def stand_in_denoiser(clean: np.ndarray, steps: int, noise: float, seed: int = 0) -> Denoiser:
    """A callable standing in for a model: each step moves the sample 30 % of the way to ``clean``,
    smooths it over 5 frames and adds Gaussian noise of ``noise * (remaining steps / steps)`` m."""
    rng = np.random.default_rng(seed)

    def denoise(x: np.ndarray, step: int) -> np.ndarray:
        x = x + 0.3 * (clean - x)
        pad = np.concatenate([x[:1].repeat(2, 0), x, x[-1:].repeat(2, 0)])
        x = sum(pad[i:i + len(x)] for i in range(5)) / 5.0
        sigma = noise * (steps - 1 - step) / steps
        return (x + sigma * rng.standard_normal(x.shape)).astype(np.float32)

    return denoise


def sample(denoise: Denoiser, x: np.ndarray, steps: int, every: int, robot: str) -> np.ndarray:
    """Run ``steps`` denoising steps from ``x``, projecting onto the robot after every ``every``
    steps (and after the last one); prints what each projection changed."""
    rb = load_robot(robot)
    for step in range(steps):
        x = denoise(x, step)
        if (step + 1) % every and step != steps - 1:
            continue
        t0 = time.perf_counter()
        p = project(x, rb)  # x: (T, 22, 3) HumanML3D joints; p.positions: the same layout
        dt = time.perf_counter() - t0
        jd = p.joint_distance
        worst = sorted(jd, key=jd.get, reverse=True)[:3]
        print(f"step {step + 1:3d}/{steps}: projected in {dt:.1f} s; {p.summary()}")
        print("           moved most: " + ", ".join(f"{k} {100 * jd[k]:.1f} cm" for k in worst)
              + f"; retargeting human' again: {p.idempotence_rms:.4f} rad RMS from the robot motion")
        x = p.positions.astype(np.float32)  # the sampler continues from what the robot can do
    return x


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("clip", nargs="?", help="HumanML3D joints .npy (T, 22, 3), y up (default: the bundled demo)")
    ap.add_argument("--steps", type=int, default=20, help="denoising steps (default 20)")
    ap.add_argument("--every", type=int, default=10, help="project every k steps (default 10)")
    ap.add_argument("--noise", type=float, default=0.03, help="initial noise, metres (default 0.03)")
    ap.add_argument("--frames", type=int, default=None, help="use the first N frames of the clip")
    ap.add_argument("--robot", default="op3")
    ap.add_argument("--out", help="save the final sample here (.npy, same layout)")
    args = ap.parse_args()
    path = Path(args.clip) if args.clip else Path(str(resources.files("motion2robot") / "data" / "demo_wave_squat.npy"))
    clean = np.load(path)[: args.frames].astype(np.float32)
    if clean.ndim != 3 or clean.shape[1:] != (22, 3):
        print(f"{path}: shape {clean.shape}, expected HumanML3D joints (T, 22, 3)", file=sys.stderr)
        return 2
    rng = np.random.default_rng(1)
    x = clean + args.noise * rng.standard_normal(clean.shape).astype(np.float32)
    print(f"sampling {path.name}: {len(clean)} frames, {args.steps} steps, projection onto {args.robot} "
          f"every {args.every} steps")
    x = sample(stand_in_denoiser(clean, args.steps, args.noise), x, args.steps, args.every, args.robot)
    d = np.linalg.norm(x - clean, axis=-1)
    print(f"final sample vs the clean clip: mean {100 * d.mean():.1f} cm, largest joint "
          f"{100 * d.mean(axis=0).max():.1f} cm (the robot's version of the clip)")
    if args.out:
        np.save(args.out, x)
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Build the bundled demo motion: a procedurally generated person who stands, waves the right
hand, lowers it, squats and rises (6 s at 20 fps), in HumanML3D joint format: (T, 22, 3) float32,
metres, y up, SMPL22 joint order, facing +z with the left hip at +x, root at x = z = 0 in frame 0,
lowest foot joint on the floor (y = 0).

    python scripts/make_demo_motion.py            # writes motion2robot/data/demo_wave_squat.npy
    python scripts/make_demo_motion.py --check    # exit 1 if the shipped file differs

Nothing is copied from a data set: adult proportions are typed in below (metres) and every joint
follows from them by a few lines of kinematics.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

FPS = 20.0
SECONDS = 6.0
OUT = Path(__file__).resolve().parents[1] / "motion2robot" / "data" / "demo_wave_squat.npy"

# rest pose, canonical frame (x forward, y left, z up), metres
HIP = np.array([0.0, 0.09, 0.88])
THIGH, SHIN = 0.40, 0.41
ANKLE = np.array([-0.02, 0.09, 0.07])
TOE = np.array([0.11, 0.09, 0.0])
UPPER_ARM, FOREARM = 0.28, 0.25
SPINE = {"spine1": 0.10, "spine2": 0.23, "spine3": 0.28, "neck": 0.50, "head": 0.63}  # above the pelvis
COLLAR = np.array([0.0, 0.07, 0.43])   # from the pelvis
SHOULDER = np.array([0.0, 0.17, 0.45])


def _smooth(t: np.ndarray, a: float, b: float) -> np.ndarray:
    """0 before a, 1 after b, smooth (cubic) in between."""
    u = np.clip((t - a) / (b - a), 0.0, 1.0)
    return u * u * (3 - 2 * u)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _knee(hip: np.ndarray, ankle: np.ndarray) -> np.ndarray:
    """Knee of a two-link leg from hip to ankle, bending forward (+x), per frame."""
    d = ankle - hip
    dist = np.linalg.norm(d, axis=-1, keepdims=True)
    along = (THIGH ** 2 - SHIN ** 2 + dist ** 2) / (2 * dist)
    side = np.sqrt(np.maximum(THIGH ** 2 - along ** 2, 0.0))
    fwd = _unit(np.cross(np.cross(d, [1.0, 0.0, 0.0]), d))  # perpendicular to the leg, towards +x
    fwd = np.where(fwd[..., :1] < 0, -fwd, fwd)
    return hip + along * d / dist + side * fwd


def make_demo_motion() -> np.ndarray:
    """(120, 22, 3) float32 HumanML3D joints (y up) of the wave-and-squat demo."""
    t = np.arange(int(SECONDS * FPS)) / FPS
    T = len(t)
    squat = _smooth(t, 3.6, 4.4) - _smooth(t, 4.8, 5.6)            # 0 -> 1 -> 0
    raise_arm = _smooth(t, 0.8, 1.5) - _smooth(t, 2.9, 3.5)        # right arm up and down again
    wave = 0.45 * np.sin(2 * np.pi * 1.8 * (t - 1.5)) * _smooth(t, 1.4, 1.7) * (1 - _smooth(t, 2.7, 3.0))
    pelvis = np.stack([-0.12 * squat, np.zeros(T), 0.95 - 0.30 * squat + 0.004 * np.sin(2 * np.pi * 0.3 * t)], -1)
    lean = 0.45 * squat                                                # torso pitch forward (rad)
    up = np.stack([np.sin(lean), np.zeros(T), np.cos(lean)], -1)      # torso axis
    fwd = np.stack([np.cos(lean), np.zeros(T), -np.sin(lean)], -1)
    left = np.array([0.0, 1.0, 0.0])

    def torso(offset: np.ndarray) -> np.ndarray:  # a point fixed in the torso (x fwd, y left, z up)
        return pelvis + offset[0] * fwd + offset[1] * left + offset[2] * up

    j: dict[str, np.ndarray] = {"pelvis": pelvis}
    for side, s in (("left", 1.0), ("right", -1.0)):
        hip = pelvis + np.array([0.0, s * HIP[1], HIP[2] - 0.95])
        ankle = np.broadcast_to(ANKLE * [1, s, 1], (T, 3))
        j[f"{side}_hip"], j[f"{side}_ankle"] = hip, ankle
        j[f"{side}_knee"] = _knee(hip, ankle)
        j[f"{side}_foot"] = np.broadcast_to(TOE * [1, s, 1], (T, 3))
        j[f"{side}_collar"] = torso(COLLAR * [1, s, 1])
        j[f"{side}_shoulder"] = torso(SHOULDER * [1, s, 1])
    for name, h in SPINE.items():
        j[name] = torso(np.array([0.03 if name == "head" else 0.0, 0.0, h]))
    # arms: hanging (slightly bent forward); arms reach forward a little in the squat
    hang_upper = _unit(np.array([0.05, 0.06, -1.0]))
    for side, s in (("left", 1.0), ("right", -1.0)):
        reach = squat[:, None] * _unit(np.array([1.0, 0.0, -0.3]))
        upper = _unit(hang_upper * [1, s, 1] + 1.2 * reach)
        fore = _unit(np.array([0.35, 0.0, -1.0]) + 1.5 * reach)
        if side == "right":  # the wave: upper arm out and up, forearm up, swinging sideways
            up_arm = _unit(np.array([0.15, -0.9, 0.45]))
            upper = _unit((1 - raise_arm)[:, None] * upper + raise_arm[:, None] * up_arm)
            fore_wave = np.stack([0.1 * np.ones(T), -np.sin(wave), np.cos(wave)], -1)
            fore = _unit((1 - raise_arm)[:, None] * fore + raise_arm[:, None] * fore_wave)
        j[f"{side}_elbow"] = j[f"{side}_shoulder"] + UPPER_ARM * upper
        j[f"{side}_wrist"] = j[f"{side}_elbow"] + FOREARM * fore
    order = ("pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2", "left_ankle",
             "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar", "right_collar", "head",
             "left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist")
    canon = np.stack([np.broadcast_to(j[k], (T, 3)) for k in order], axis=1)   # (T, 22, 3) z up
    canon[..., 2] -= canon[..., 2].min()                                        # lowest joint on the floor
    hml = np.stack([canon[..., 1], canon[..., 2], canon[..., 0]], axis=-1)     # y up, facing +z, left = +x
    hml[..., [0, 2]] -= hml[0, 0, [0, 2]]                                       # root at x = z = 0 in frame 0
    return np.round(hml, 5).astype(np.float32)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="compare with the shipped file instead of writing")
    ap.add_argument("-o", "--output", type=Path, default=OUT)
    args = ap.parse_args(argv)
    motion = make_demo_motion()
    if args.check:
        same = args.output.is_file() and np.array_equal(np.load(args.output), motion)
        print(f"{args.output}: {'matches' if same else 'DIFFERS from'} make_demo_motion()")
        return 0 if same else 1
    args.output.parent.mkdir(parents=True, exist_ok=True)
    np.save(args.output, motion)
    print(f"wrote {args.output}: {motion.shape} float32, {args.output.stat().st_size} bytes, {len(motion) / FPS:.1f} s at {FPS:g} fps")
    return 0


if __name__ == "__main__":
    sys.exit(main())

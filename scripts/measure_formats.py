"""Figures of the issue-17 readers on ../shared/motions (prints them; no assertions).

1. MotionFix 207-d: HumanML3D clips encoded by the test-side encoder, decoded back (float64 and
   float32 files, and normalised with a statistics dict): max joint error after the canonical frame.
2. Body model: FK through a SMPL-H-layout fixture vs an independent 4x4 computation.
3. The built-in approximate skeleton: the AIST++ .pkl read with it vs the same motion as MoMask's
   BVH (SMPL neutral rest skeleton).
4. Automatic skeleton map: shared BVHs read without a name map, renamed copies vs originals, and
   the time to read a renamed copy relative to the original (best of 3, same run).

Run: python scripts/measure_formats.py  (needs ../shared/motions)
"""

from __future__ import annotations

import pickle
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from motion2robot.motion import read_motion  # noqa: E402
from tests._shared import MOTIONS  # noqa: E402


def _best(f, n: int = 3) -> float:
    out = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        out.append(time.perf_counter() - t0)
    return min(out)


def motionfix(tmp: Path) -> None:
    from tests.motionfix_encoder import encode

    for p in sorted((MOTIONS / "humanml3d_joints").glob("*.npy")):
        src = read_motion(p)[0]
        if p.name.startswith("000021"):
            continue
        feat = encode(src.positions)
        errs = []
        for dtype in (np.float64, np.float32):
            np.save(tmp / "f.npy", feat.astype(dtype))
            errs.append(np.linalg.norm(read_motion(tmp / "f.npy")[0].positions - src.positions, axis=-1).max())
        mean, std = feat.mean(0), feat.std(0) + 1e-3
        (tmp / "s.pkl").write_bytes(pickle.dumps({"mean": mean, "std": std}))
        np.save(tmp / "n.npy", ((feat - mean) / std).astype(np.float32))
        errs.append(np.linalg.norm(read_motion(tmp / "n.npy", stats=tmp / "s.pkl")[0].positions - src.positions,
                                   axis=-1).max())
        print(f"207-d {p.name} ({src.num_frames} frames): max joint error float64 {errs[0] * 1e3:.2e} mm, "
              f"float32 {errs[1] * 1e3:.1e} mm, normalised float32 + stats {errs[2] * 1e3:.1e} mm")


def body_model(tmp: Path) -> None:
    from motion2robot.motion.body_model import joint_positions, load_body_model
    from tests.test_motion_body_model import _independent_fk, _motion, _quat_matrix, smplh_fixture

    path = smplh_fixture(tmp / "model.npz")
    aa, trans = _motion(200)
    rot = _quat_matrix(aa)
    betas = np.linspace(-1, 1, 16)
    err = np.abs(joint_positions(load_body_model(path, betas), rot, trans)
                 - _independent_fk(path, rot, trans, betas)).max()
    print(f"body model FK (SMPL-H layout fixture, 200 frames, 16 betas) vs independent 4x4 chain: max {err:.2e} m")


def approximate() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = read_motion(MOTIONS / "smpl" / "aistpp_gBR_sBM_cAll_d04_mBR0_ch01.pkl")[0]
    b = read_motion(MOTIONS / "bvh" / "momask_template_aistpp_gBR.bvh")[0]
    e = np.linalg.norm(a.positions - b.positions, axis=-1)
    print(f"approximate skeleton vs SMPL neutral (AIST++ gBR, {a.num_frames} frames): joint error mean "
          f"{e.mean() * 100:.1f} cm, max {e.max() * 100:.1f} cm")


def auto_map(tmp: Path) -> None:
    from tests.test_motion_auto_map import _renamed

    files = sorted((MOTIONS / "bvh").glob("*.bvh"))
    worst, ratios = 0.0, []
    for f in files:
        orig = read_motion(f)[0]
        copy_path = _renamed(f, tmp / f.name, 0)
        copy = read_motion(copy_path)[0]
        worst = max(worst, float(np.abs(copy.positions - orig.positions).max()))
        ratios.append(_best(lambda: read_motion(copy_path)) / _best(lambda: read_motion(f)))
    print(f"automatic map: {len(files)}/{len(files)} shared BVHs read without --name-map; renamed copies vs "
          f"originals max difference {worst:.1e} m; read time renamed/original median {np.median(ratios):.2f}x "
          f"(max {max(ratios):.2f}x)")


def main() -> int:
    if MOTIONS is None:
        print("../shared/motions is absent")
        return 1
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        motionfix(tmp)
        body_model(tmp)
        approximate()
        auto_map(tmp)
    return 0


if __name__ == "__main__":
    sys.exit(main())

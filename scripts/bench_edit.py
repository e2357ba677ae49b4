"""Cost of ``retarget_edit`` (a right-arm edit in frames 40-80), without and with the balance
override, relative to one ``retarget`` of the source, best of 3 after a warm-up, on real clips of
../shared/motions (op3). Prints the ratios.

Run: python scripts/bench_edit.py
"""

from __future__ import annotations

import sys
import timeit
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from motion2robot.edit import retarget_edit  # noqa: E402
from motion2robot.motion import read_motion  # noqa: E402
from motion2robot.motion.human import KP, HumanMotion  # noqa: E402
from motion2robot.retarget import retarget  # noqa: E402
from motion2robot.robot import load_robot  # noqa: E402
from tests._shared import MOTIONS  # noqa: E402


def arm_edit(m: HumanMotion) -> HumanMotion:
    p = m.positions.copy()
    ang = np.zeros(m.num_frames)
    ang[40:81] = 0.8 * np.sin(np.linspace(0, np.pi, 41))
    c, s = np.cos(ang), np.sin(ang)
    sh = p[:, KP["right_shoulder"]]
    for k in (KP["right_elbow"], KP["right_wrist"]):
        d = p[:, k] - sh
        p[:, k, 1], p[:, k, 2] = sh[:, 1] + c * d[:, 1] - s * d[:, 2], sh[:, 2] + s * d[:, 1] + c * d[:, 2]
    return HumanMotion(p, m.fps, meta=dict(m.meta))


def main() -> int:
    if MOTIONS is None:
        print("../shared/motions is absent")
        return 1
    robot = load_robot("op3")
    for rel in ("humanml3d_joints/012314.npy", "humanml3d_joints/007005.npy", "bvh/bandai_walk_normal_001.bvh",
                "bvh/bandai_dance-short_normal_001.bvh"):
        src = read_motion(MOTIONS / rel)[0]
        edit = arm_edit(src)
        retarget(src, robot)  # warm-up (compiled problem, caches)
        t_r = min(timeit.repeat(lambda: retarget(src, robot), number=1, repeat=3))
        t_e = min(timeit.repeat(lambda: retarget_edit(src, edit, robot), number=1, repeat=3))
        t_b = min(timeit.repeat(lambda: retarget_edit(src, edit, robot, balance_override=True), number=1, repeat=3))
        print(f"{rel} ({src.num_frames} frames): retarget {t_r:.2f} s, edit {t_e:.2f} s = {t_e / t_r:.2f}x one "
              f"retarget; with balance override {t_b:.2f} s = {t_b / t_r:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())

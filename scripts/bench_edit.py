"""Cost of ``retarget_edit`` (a right-arm edit in frames 40-80; balance override allowed, as by
default) relative to one ``retarget`` of the source, best of 3 interleaved runs after a warm-up, on real clips of
../shared/motions (op3), and the invariance figure: the largest difference between the edited and
the source robot motion over every hinge not driven by the right arm, and over the root, in all
frames (rad; metres / quaternion for the root). Prints the ratios and figures.

Run: python scripts/bench_edit.py
"""

from __future__ import annotations

import sys
import time
import timeit
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from motion2robot.edit import retarget_edit  # noqa: E402
from motion2robot.edit.parts import hinge_parts  # noqa: E402
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
        t_r, t_e = [], []
        for _ in range(3):  # interleaved, so both see the same load of the shared machine
            t_r.append(min(timeit.repeat(lambda: retarget(src, robot), number=1, repeat=1)))
            t0 = time.perf_counter()
            r = retarget_edit(src, edit, robot)
            t_e.append(time.perf_counter() - t0)
        t_r, t_e = min(t_r), min(t_e)
        kept = np.array([h for h, ps in enumerate(hinge_parts(robot)) if "right_arm" not in ps])
        d = np.abs(r.edited.qpos - r.source.qpos)
        o = r.info["balance_override"]
        print(f"{rel} ({src.num_frames} frames): retarget {t_r:.2f} s, edit {t_e:.2f} s = {t_e / t_r:.2f}x one "
              f"retarget (its parts: {r.info['seconds']}); kept hinges max |edited - source| {d[:, 7 + kept].max():.1e} rad, root {d[:, :7].max():.1e}; "
              f"override {o['frames'] if o else 'none'}; edit window {r.info['retargeted_window']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

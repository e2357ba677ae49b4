"""Drafted robots, judged without edits: ``robots init`` on every humanoid in the Menagerie folder,
then load, retarget real clips and check them.

    MENAGERIE_ROOT=../shared/menagerie python scripts/bench_drafts.py [--robots op3,g1] [--clips N]

Prints per robot: hinges, keypoint distance to the joint centre it stands for (mean and worst,
centres from the MJCF's joint positions: ``tests/_joint_centres.py``), the model's own overlaps
at the drafted nominal pose, and over the clips: joint-limit violations, frames with a geom more
than the check's tolerance below the floor (and the deepest sole corner), frames with
self-collision beyond the model's own nominal overlaps (and the deepest), frames per second.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from motion2robot.motion import read_motion  # noqa: E402
from motion2robot.retarget import RetargetOptions, retarget  # noqa: E402
from motion2robot.retarget.metrics import acceptance  # noqa: E402
from motion2robot.robot import load_robot  # noqa: E402
from motion2robot.robot.draft import draft_config, write_draft  # noqa: E402
from motion2robot.validate import check  # noqa: E402
from motion2robot.validate.collision import nominal_overlaps  # noqa: E402
from motion2robot.validate.options import CheckOptions  # noqa: E402
from tests._joint_centres import JOINTS, keypoint_errors  # noqa: E402


def shared_dir() -> Path:
    env = os.environ.get("MOTION2ROBOT_SHARED")
    return Path(env) if env else ROOT.parent / "shared"


def clips(n: int):
    out = [("demo", read_motion(ROOT / "motion2robot" / "data" / "demo_wave_squat.npy")[0])]
    for p in sorted((shared_dir() / "motions" / "humanml3d_joints").glob("*.npy"))[:n]:
        out += [(p.name, h) for h in read_motion(p)[:1]]
    return out


def judge(name: str, humans, workdir: Path, options: RetargetOptions) -> dict:
    draft = draft_config(f"menagerie:{name}", name=f"{name}_draft")
    robot = load_robot(str(write_draft(draft, workdir / f"{name}.toml")))
    err = keypoint_errors(name, robot)
    row = {"robot": name, "hinges": robot.n_joints, "kp_mean_mm": 1000 * np.mean(list(err.values())),
           "kp_max_mm": 1000 * max(err.values()), "kp_worst": max(err, key=err.get), "n_kp": len(err),
           "overlaps": len(nominal_overlaps(robot)), "limit": 0, "below": 0, "sole_mm": 0.0, "coll_frames": 0,
           "coll_mm": 0.0, "frames": 0, "seconds": 0.0}
    for _, human in humans:
        t0 = time.perf_counter()
        motion = retarget(human, robot, options)
        row["seconds"] += time.perf_counter() - t0
        a = acceptance(motion, robot, collisions=False)
        rep = check(motion, robot, CheckOptions(physics=False))
        sc, gr = rep.checks["self_collision"], rep.checks["ground"]
        row["frames"] += motion.num_frames
        row["limit"] += a["limit_violations"]
        row["below"] += len({f for p in gr.get("penetrations", []) for f in p["frames"]})
        row["sole_mm"] = max(row["sole_mm"], a["sole_depth_mm"])
        row["coll_frames"] += len(sc["frames"])
        row.setdefault("pairs", set()).update(f"{v['body1']}/{v['body2']}" for v in sc["violations"])
        row["coll_mm"] = max(row["coll_mm"], 1000 * sc["max_depth_m"])
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--robots", default=",".join(JOINTS), help="comma-separated Menagerie folder names")
    ap.add_argument("--clips", type=int, default=5, help="HumanML3D joint clips of ../shared/motions (plus the demo)")
    ap.add_argument("--backend", default=None, help="retarget backend (default: compiled C; 'vm': no compilation)")
    args = ap.parse_args()
    options = RetargetOptions() if args.backend is None else RetargetOptions(backend=args.backend)
    if not os.environ.get("MENAGERIE_ROOT"):
        sys.exit("set MENAGERIE_ROOT (e.g. ../shared/menagerie)")
    humans = clips(args.clips)
    print(f"{len(humans)} clips, {sum(h.num_frames for _, h in humans)} human frames")
    head = (f"{'robot':12s} {'hinges':>6s} {'kp mean/max mm (worst)':>34s} {'own overlaps':>12s} {'limit viol':>10s} "
            f"{'frames below floor':>18s} {'sole mm':>7s} {'self-coll frames':>16s} {'deepest mm':>10s} {'frames/s':>8s}")
    print(head)
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.robots.split(","):
            r = judge(name, humans, Path(tmp), options)
            kp = f"{r['kp_mean_mm']:.1f} / {r['kp_max_mm']:.1f} ({r['kp_worst']}, {r['n_kp']} kps)"
            print(f"{name:12s} {r['hinges']:6d} {kp:>34s} {r['overlaps']:12d} {r['limit']:10d} {r['below']:18d} "
                  f"{r['sole_mm']:7.2f} {r['coll_frames']:16d} {r['coll_mm']:10.2f} {r['frames'] / r['seconds']:8.0f}",
                  flush=True)
            if r.get("pairs"):
                print(f"{'':12s} self-collision: {', '.join(sorted(r['pairs']))}")


if __name__ == "__main__":
    main()

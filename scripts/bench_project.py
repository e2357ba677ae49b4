"""Benchmark of ``project(human) -> human'`` over the dev clips (one row per clip, as ``batch``
expands ../shared/motions).

Per clip, prints:
- idempotence: RMS (rad, over frames and hinges) between the robot motion of ``human`` and the
  default retargeting (tempo and legs judged by ``check``) of ``human'``; ``direct`` is the same
  figure for the robot's keypoints mapped back without the target correction (retargeted at the
  correction's tempo and legs), ``same`` for the ``human'`` returned, retargeted at the tempo and
  legs of ``human``'s robot motion (the correction's own figure, its best round: the default
  retargeting may pick another legs mode or tempo for ``human'``), ``rounds`` how many correction
  rounds ran (against the solves alone + against the whole retargeting);
  "tempo differs" when the policy picked another tempo for ``human'`` (motions of different
  lengths);
- keypoints: mean distance (mm, robot scale) between the robot's keypoints in the two robot
  motions, the same comparison in space (a nearly straight knee moves its keypoint by 0.05 mm per
  mrad: the hinge RMS weighs such ill-conditioned joints heavily);
- executability before (``human``'s robot motion) and after (``human'``'s), both the full
  ``check`` with the physics playback, as the policy judged them;
- the per-joint distance between ``human`` and ``human'`` (cm, mean over frames; mean over
  joints and the largest joint);
- noise: the retargeting's own sensitivity, the floor under idempotence: RMS (rad) between the
  robot motion of ``human`` and the retargeting (made the same way: tempo, legs, replay) of ``human`` moved by
  Gaussian noise of NOISE_M (0.01 mm, far below any capture's or generator's precision);
- the time of ``project`` per clip (wall seconds, on a shared 2-core machine).

Run:  python scripts/bench_project.py [--robot op3] [--limit N] [--rounds 6] [--csv out.csv]
"""

from __future__ import annotations

import sys
import time

import numpy as np

from _clips import clips_parser, motions_missing, readable_clips
from motion2robot.motion.human import SMPL22
from motion2robot.projection import ROUNDS, TOLERANCE, chosen_solve, hinge_rms, project, robot_points
from motion2robot.retarget.executable import legs_of
from motion2robot.retarget.remake import remake
from motion2robot.retarget import retarget_and_check
from motion2robot.robot import load_robot



#: m, standard deviation of the noise added to every joint coordinate for the sensitivity column.
NOISE_M = 1e-5


def sensitivity(p, robot) -> float:
    """RMS (rad) between ``p``'s robot motion and the retargeting of its human moved by NOISE_M
    Gaussian noise (a fixed seed), made as the robot motion was (:func:`remake`: its tempo, legs
    and replay, nothing judged)."""
    h = p.original
    noisy = h.with_(positions=np.asarray(h.positions) + NOISE_M * np.random.default_rng(0).standard_normal(np.shape(h.positions)))
    return hinge_rms(p.robot_motion, remake(noisy, robot, p.robot_motion))


def _verdict(ok: bool | None) -> str:
    return {True: "yes", False: "no", None: "-"}[ok]


def keypoint_gap_mm(a, b, robot) -> float:
    """Mean distance (mm) between the tracked keypoints of two robot motions of the same length."""
    if a.qpos.shape != b.qpos.shape:
        return float("nan")
    pa, mapped, _ = robot_points(a, robot)
    pb, _, _ = robot_points(b, robot)
    return 1000.0 * float(np.linalg.norm(pa - pb, axis=-1)[:, mapped].mean())


def main() -> int:
    ap = clips_parser(__doc__)
    ap.add_argument("--rounds", type=int, default=ROUNDS, help=f"correction rounds at most (default {ROUNDS})")
    args = ap.parse_args()
    if motions_missing(args.motions):
        return 2
    robot = load_robot(args.robot)
    rows = []
    print(f"{'clip':44s} {'idem rad':>9s} {'kp mm':>6s} {'direct':>7s} {'same':>7s} {'rnds':>5s} {'legs':>6s} "
          f"{'noise':>7s} {'exe before':>10s} {'after':>5s} "
          f"{'dist cm':>7s} {'worst joint':>20s} {'time s':>6s}")
    for name, human in readable_clips(args.motions, args.limit, args.only):
        t0 = time.perf_counter()
        try:
            p = project(human, robot, rounds=args.rounds)
        except Exception as err:  # noqa: BLE001
            print(f"  FAIL {name}: project: {str(err).splitlines()[0][:160]}")
            continue
        dt = time.perf_counter() - t0
        again, report = retarget_and_check(p.human, robot)
        rms = hinge_rms(p.robot_motion, again)
        gap = keypoint_gap_mm(p.robot_motion, again, robot)
        noise = sensitivity(p, robot)
        jd = p.joint_distance
        worst = max(jd, key=jd.get)
        direct = hinge_rms(p.robot_motion, chosen_solve(p.robot_motion, robot, None)(p.direct))
        row = {"clip": name, "idempotence": rms, "kp_mm": gap, "direct": direct, "same": min(p.rounds),
               "rounds": "exact" if p.reached else f"{len(p.solver_rounds)}+{len(p.rounds)}",
               "noise": noise,
               "legs": legs_of(p.robot_motion),
               "tempo": float(p.robot_motion.meta.get("tempo", 1.0)),
               "tempo_again": float(again.meta.get("tempo", 1.0)),
               "before": p.executable, "after": None if report is None else bool(report.feasible),
               "drift": p.bone_drift, "dist_cm": 100 * p.mean_distance, "worst": worst, "worst_cm": 100 * jd[worst], "time_s": dt,
               "joint_cm": {k: 100 * v for k, v in jd.items()}}
        rows.append(row)
        idem = f"{rms:9.4f}" if np.isfinite(rms) else f"{'tempo differs':>9s}"
        print(f"{name[:44]:44s} {idem} {gap:6.2f} {row['direct']:7.4f} {row['same']:7.4f} {row['rounds']:>5s} {row['legs']:>6s} "
              f"{noise:7.4f} {_verdict(row['before']):>10s} "
              f"{_verdict(row['after']):>5s} {row['dist_cm']:7.1f} {worst:>14s} {row['worst_cm']:5.1f} {dt:6.1f}",
              flush=True)
    if not rows:
        print("no clip projected")
        return 1
    same = [r for r in rows if np.isfinite(r["idempotence"])]
    idem = np.array([r["idempotence"] for r in same])
    direct = np.array([r["direct"] for r in rows if np.isfinite(r["direct"])])
    print(f"\n{robot.name}: {len(rows)} clips projected")
    if same:
        print(f"idempotence (default retargeting of human' vs of human), hinge RMS: median {np.median(idem):.4f} rad, "
              f"max {idem.max():.4f} rad; within {TOLERANCE:g} rad: {int((idem <= TOLERANCE).sum())}/{len(same)}; "
              f"within 0.01 rad: {int((idem <= 0.01).sum())}/{len(same)}")
        gaps = np.array([r["kp_mm"] for r in same])
        print(f"the same comparison in space, robot keypoints: median {np.median(gaps):.2f} mm, "
              f"max {gaps.max():.2f} mm")
    own = np.array([r["same"] for r in rows if np.isfinite(r["same"])])
    if len(own):
        print(f"at the tempo and legs of human's robot motion (the correction's own figure, its best round): median "
              f"{np.median(own):.4f} rad, max {own.max():.4f} rad; within {TOLERANCE:g} rad: "
              f"{int((own <= TOLERANCE).sum())}/{len(own)}; within 0.01 rad: {int((own <= 0.01).sum())}/{len(own)}")
    noise = np.array([r["noise"] for r in rows])
    print(f"the retargeting's own sensitivity (the same tempo and legs, the human moved by {1000 * NOISE_M:g} mm "
          f"noise), hinge RMS: median {np.median(noise):.4f} rad, max {noise.max():.4f} rad; within {TOLERANCE:g} rad: "
          f"{int((noise <= TOLERANCE).sum())}/{len(noise)}")
    if len(direct):
        print(f"without the target correction (direct mapping back): median {np.median(direct):.4f} rad, "
              f"max {direct.max():.4f} rad")
    print(f"tempo chosen differently for human': {len(rows) - len(same)} clips")
    was = [r for r in rows if r["before"]]
    kept = [r for r in was if r["after"]]
    print(f"executable before: {len(was)}/{len(rows)}; still executable after projection: {len(kept)}/{len(was)}"
          + (f" (lost: {', '.join(r['clip'] for r in was if not r['after'])})" if len(kept) < len(was) else ""))
    gained = [r for r in rows if r["before"] is False and r["after"]]
    print(f"not executable before but executable after: {len(gained)}")
    per_joint = {k: float(np.mean([r["joint_cm"][k] for r in rows])) for k in SMPL22}
    print("per-joint distance human vs human' (cm, mean over clips): "
          + ", ".join(f"{k} {v:.1f}" for k, v in per_joint.items()))
    whole = [r["dist_cm"] for r in rows if r["legs"] == "whole"]
    print(f"mean over joints: {np.mean([r['dist_cm'] for r in rows]):.1f} cm; clips with the whole body: "
          f"{np.mean(whole) if whole else float('nan'):.1f} cm ({len(whole)} clips; a stance fallback keeps the "
          "robot in place while the person travels)")
    times = np.array([r["time_s"] for r in rows])
    drift = np.array([r["drift"] for r in rows])
    print(f"bone lengths of human' vs the direct mapping's (largest relative change of a bone in any frame): "
          f"median {100 * np.median(drift):.2f} %, max {100 * drift.max():.2f} %")
    print(f"time per clip (project, wall): median {np.median(times):.1f} s, max {times.max():.1f} s")
    if args.csv:
        import csv
        with open(args.csv, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["clip", "idempotence_rad", "direct_rad", "same_legs_rad", "noise_rad", "rounds", "legs", "tempo", "tempo_again",
                        "executable_before", "executable_after", "bone_drift", "distance_cm", "worst_joint", "worst_cm", "time_s"])
            for r in rows:
                w.writerow([r["clip"], r["idempotence"], r["direct"], r["same"], r["noise"], r["rounds"], r["legs"], r["tempo"],
                            r["tempo_again"], r["before"], r["after"], round(r["drift"], 4), round(r["dist_cm"], 2), r["worst"],
                            round(r["worst_cm"], 2), round(r["time_s"], 2)])
    return 0


if __name__ == "__main__":
    sys.exit(main())

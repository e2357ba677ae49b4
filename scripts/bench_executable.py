"""Benchmark of executability: how much of the retargeted motion the robot can really perform.

Over every readable clip of ``../shared/motions`` (one row per clip, as ``batch`` expands the
folder), retargets with the default options (and, for comparison, the kinematic-only pipeline)
and runs the full ``check`` with the physics playback. Prints per clip and in total:

- executable %: ``check`` FEASIBLE, rollout included;
- stays-up %: the open-loop physics playback does not fall;
- tempo factor (median, max) and the clips on a fallback;
- keypoint error (mm, mean over frames and keypoints, of the robot's keypoints from the human's
  scaled to the robot at the motion's tempo: ``score``'s fidelity figure) and root path error
  (robot metres, mean) against the kinematic-only retarget of the same clip;
- the failing checks and how often each fails;
- the quasi-static clips (pelvis within 0.5 m of its start): how many keep the tempo (x1.00) and
  how much keypoint error they lose against the kinematic-only retarget (the target: < 20 %);
- retargeting speed in frames per CPU second, beside the kinematic-only figure (same run);
- artefacts: the clip retargeted again at 100 fps the way it was (its tempo, legs and replay:
  :func:`~motion2robot.retarget.remake.remake`), whose peak root and joint
  accelerations must stay within 1.5x of the native rate's (``--no-artefacts`` skips it); a clip
  over 1.5x gets the ratio split in two: sampling (the natural cubic spline through the native
  frames, its peak over their second difference's: what the native rate does not show of its own
  trajectory) and trajectory (the 100 fps result's peak over that spline's: how much the two
  results differ); native peaks below ROOT_FLOOR / JOINT_FLOOR count as those (negligible motion);
  and the clips with a violation confined to their first or last 2 frames.

Run:  python scripts/bench_executable.py [--robot op3] [--limit N] [--tempo auto] [--csv out.csv]
"""

from __future__ import annotations

import collections
import sys
import time

import numpy as np

from _clips import clips_parser, motions_missing, readable_clips
from motion2robot.batch.work import expand_inputs
from motion2robot.motion import read_motion
from motion2robot.retarget import RetargetOptions, retarget
from motion2robot.retarget.nearness import keypoint_error
from motion2robot.retarget.remake import remake
from motion2robot.retarget.tempo import stretch
from motion2robot.robot import load_robot
from motion2robot.validate import CheckOptions, check



def kinematic_options() -> RetargetOptions:
    """The pipeline as it was before the executability stages: kinematic retargeting only."""
    return RetargetOptions(tempo="human", legs="whole", dynamic_balance=False, lift_feet=False)


def default_options(tempo: str | None) -> RetargetOptions:
    return RetargetOptions() if tempo is None else RetargetOptions(tempo=tempo)


def keypoint_error_mm(motion, human, robot, pose: bool = False) -> float:
    """Mean distance (mm) of the robot's keypoints from the human's scaled to it, at the motion's
    tempo (the fidelity figure ``score`` reports; the solver's own residual is against the targets
    of its legs mode: a stance's stand in place, and would not count the travel it drops)."""
    return 1000.0 * keypoint_error(motion, stretch(human, float(motion.meta.get("tempo") or 1.0)), robot, pose=pose)


def _legs(row) -> str:
    return row["fallback"]["mode"] if isinstance(row["fallback"], dict) else "whole"


def root_xy(motion) -> np.ndarray:
    return np.asarray(motion.qpos[:, :2])


def path_error(a, b) -> float:
    """Mean distance (m) between two root paths, b resampled onto a's duration."""
    pa, pb = root_xy(a), root_xy(b)
    ta = np.linspace(0.0, 1.0, len(pa))
    tb = np.linspace(0.0, 1.0, len(pb))
    pbr = np.stack([np.interp(ta, tb, pb[:, i]) for i in range(2)], axis=1)
    return float(np.linalg.norm(pa - pbr, axis=1).mean())


def peak_accelerations(motion) -> tuple[float, float]:
    """(root m/s^2, joint rad/s^2) peak second differences."""
    acc = np.diff(motion.qpos, 2, axis=0) * motion.fps ** 2
    return float(np.abs(acc[:, :3]).max()), float(np.abs(acc[:, 7:]).max())


#: m/s^2 and rad/s^2: native peaks below these count as these in the 100 fps ratio (a motion that
#: stands still natively would otherwise divide by ~0; a servo's own limit is ~100 rad/s^2).
ROOT_FLOOR = 0.5
JOINT_FLOOR = 5.0


def spline_accelerations(motion) -> tuple[float, float]:
    """(root m/s^2, joint rad/s^2) peak second derivatives of the natural cubic spline through the
    frames: what the samples themselves imply between them. The spline's second derivative is
    linear between frames, so its peak is at a frame: M with (M[i-1] + 4 M[i] + M[i+1]) / 6 = the
    second difference at i, M = 0 at both ends (a tridiagonal solve, Thomas algorithm)."""
    q = np.concatenate([motion.qpos[:, :3], motion.qpos[:, 7:]], axis=1)
    rhs = 6.0 * np.diff(q, 2, axis=0) * motion.fps ** 2
    n = len(rhs)
    if n == 0:
        return 0.0, 0.0
    c, d = np.zeros(n), np.zeros_like(rhs)
    c[0], d[0] = 1.0 / 4.0, rhs[0] / 4.0
    for i in range(1, n):  # forward sweep (sub- and super-diagonal 1, diagonal 4)
        m = 4.0 - c[i - 1]
        c[i], d[i] = 1.0 / m, (rhs[i] - d[i - 1]) / m
    for i in range(n - 2, -1, -1):  # back substitution
        d[i] -= c[i] * d[i + 1]
    return float(np.abs(d[:, :3]).max()), float(np.abs(d[:, 3:]).max())


#: m; a clip whose pelvis stays within this of its start (horizontally) is quasi-static: stand, wave,
#: bow, squat, reach, turn in place (the issue's list), not walks.
QUASI_STATIC_REACH = 0.5


def quasi_static(human) -> bool:
    """The human pelvis never leaves a 0.5 m circle around its first position (canonical: z up)."""
    p = np.asarray(human.positions)[:, 0, :2]
    return bool(np.linalg.norm(p - p[0], axis=1).max() < QUASI_STATIC_REACH)


def edge_only(report, frames: int) -> list[str]:
    """Checks that fail only within the first or last 2 frames."""
    ends = set(range(2)) | set(range(frames - 2, frames))
    return [n for n, c in report.checks.items()
            if c.get("ok") is False and c.get("frames") and set(c["frames"]) <= ends]


def main() -> int:
    ap = clips_parser(__doc__)
    ap.add_argument("--tempo", default=None, help="tempo policy passed to retarget (default: the retargeter's)")
    ap.add_argument("--no-baseline", action="store_true", help="skip the kinematic-only comparison")
    ap.add_argument("--no-artefacts", action="store_true", help="skip the 100 fps resampling comparison")
    args = ap.parse_args()
    if motions_missing(args.motions):
        return 2
    robot = load_robot(args.robot)
    items = list(expand_inputs([args.motions]).items)[: args.limit]
    opts, base_opts = default_options(args.tempo), kinematic_options()
    copts = CheckOptions()
    retarget(read_motion(items[0].path, clip=items[0].clip)[0], robot, opts)  # compile outside the timing
    rows = []
    cpu_new = cpu_base = frames_total = 0.0
    for name, human in readable_clips(args.motions, args.limit, args.only):
        c0 = time.process_time()
        try:
            motion = retarget(human, robot, opts)
        except Exception as err:  # noqa: BLE001
            print(f"  FAIL {name}: retarget: {str(err).splitlines()[0][:160]}")
            rows.append({"clip": name, "error": str(err)})
            continue
        c1 = time.process_time()
        base = None
        if not args.no_baseline:
            base = retarget(human, robot, base_opts)
        c2 = time.process_time()
        cpu_new += c1 - c0
        cpu_base += c2 - c1
        frames_total += human.num_frames
        rep = check(motion, robot, copts)
        roll = rep.checks.get("rollout", {})
        failed = [n for n, c in rep.checks.items() if c.get("ok") is False]
        row = {
            "clip": name, "frames": human.num_frames, "feasible": rep.feasible, "stays_up": not roll.get("fell", False),
            "tempo": float(motion.meta.get("tempo", 1.0)), "fallback": motion.meta.get("fallback"),
            "kp_mm": keypoint_error_mm(motion, human, robot), "pose_mm": keypoint_error_mm(motion, human, robot, True),
            "failed": failed, "reasons": rep.reasons,
            "quasi_static": quasi_static(human),
        }
        if base is not None:
            row["kp_base_mm"] = keypoint_error_mm(base, human, robot)
            row["pose_base_mm"] = keypoint_error_mm(base, human, robot, True)
            row["path_err_m"] = path_error(motion, base)
        if not args.no_artefacts:
            fine = remake(human, robot, motion, RetargetOptions(fps=100.0))  # made as motion was (tempo, legs, replay)
            (rn, jn), (rf, jf) = peak_accelerations(motion), peak_accelerations(fine)
            rn, jn = max(rn, ROOT_FLOOR), max(jn, JOINT_FLOOR)  # a ratio of negligible peaks is no spike
            row["fine_ratio"] = max(rf / max(rn, 1e-9), jf / max(jn, 1e-9))
            row["fine"] = f"root {rf / max(rn, 1e-9):.2f}x ({rn:.1f} -> {rf:.1f} m/s^2), joints {jf / max(jn, 1e-9):.2f}x ({jn:.0f} -> {jf:.0f} rad/s^2)"
            rs, js = spline_accelerations(motion)
            rs, js = max(rs, ROOT_FLOOR), max(js, JOINT_FLOOR)
            # the ratio of the failing quantity split in two: what the native frames imply between them
            # (sampling: their spline's peak over their second difference's) and how much the 100 fps
            # result itself differs from that spline (trajectory)
            worse = (rs, rn, rf) if rf / max(rn, 1e-9) >= jf / max(jn, 1e-9) else (js, jn, jf)
            row["sampling"] = worse[0] / max(worse[1], 1e-9)
            row["trajectory"] = worse[2] / max(worse[0], 1e-9)
            row["fine"] += f" = sampling {row['sampling']:.2f} x trajectory {row['trajectory']:.2f}"
        row["edge_only"] = edge_only(rep, motion.num_frames)
        rows.append(row)
        fb = f" fallback={row['fallback']['mode']}" if isinstance(row["fallback"], dict) else ""
        print(f"  {'OK  ' if rep.feasible else 'FAIL'} {name:48s} up={row['stays_up']!s:5s} tempo={row['tempo']:.2f}"
              f"{fb} kp={row['kp_mm']:.1f}mm" + (f" (kin {row['kp_base_mm']:.1f})" if base is not None else "")
              + (f" failed={','.join(failed)}" if failed else "")
              + (f" 100fps: {row['fine']}" if row.get("fine_ratio", 0) > 1.5 else ""), flush=True)
    ok = [r for r in rows if "error" not in r]
    n = len(ok)
    if not n:
        print("no clip retargeted")
        return 1
    tempos = np.array([r["tempo"] for r in ok])
    counts = collections.Counter(c for r in ok for c in r["failed"])
    print(f"\n{robot.name}: {n} clips ({len(rows) - n} retarget errors), {int(frames_total)} frames")
    print(f"executable (check FEASIBLE, rollout included): {sum(r['feasible'] for r in ok)}/{n} = "
          f"{100 * np.mean([r['feasible'] for r in ok]):.1f} %")
    print(f"stays up in open-loop playback: {sum(r['stays_up'] for r in ok)}/{n} = {100 * np.mean([r['stays_up'] for r in ok]):.1f} %")
    print(f"tempo factor: median {np.median(tempos):.2f}, max {tempos.max():.2f}; clips on a fallback: "
          f"{sum(1 for r in ok if r['fallback'])}")
    print("failing checks: " + (", ".join(f"{k} {v}" for k, v in counts.most_common()) or "none"))
    kp = np.array([r["kp_mm"] for r in ok])
    if not args.no_baseline:
        kb = np.array([r["kp_base_mm"] for r in ok])
        pe = np.array([r["path_err_m"] for r in ok])
        print(f"keypoint error: {kp.mean():.1f} mm (kinematic-only {kb.mean():.1f} mm, {100 * (kp.mean() / kb.mean() - 1):+.0f} %); "
              f"root path vs kinematic-only: mean {pe.mean() * 100:.1f} cm, max {pe.max() * 100:.1f} cm")
        pose, pb = np.array([r["pose_mm"] for r in ok]), np.array([r["pose_base_mm"] for r in ok])
        print(f"  the posture alone (keypoints relative to the pelvis): {pose.mean():.1f} mm (kinematic-only "
              f"{pb.mean():.1f} mm); by legs: " + ", ".join(
                  f"{legs} {np.mean([r['kp_mm'] for r in grp]):.1f} / {np.mean([r['pose_mm'] for r in grp]):.1f} mm "
                  f"({len(grp)})" for legs in ("whole", "steps", "stance")
                  if (grp := [r for r in ok if _legs(r) == legs])))
        print(f"speed: {frames_total / cpu_new:,.0f} frames per CPU second (kinematic-only {frames_total / cpu_base:,.0f}, same run)")
        qs = [r for r in ok if r["quasi_static"]]
        if qs:
            loss = np.array([r["kp_mm"] / max(r["kp_base_mm"], 1e-9) - 1.0 for r in qs])
            worst = max(qs, key=lambda r: r["kp_mm"] / max(r["kp_base_mm"], 1e-9))
            print(f"quasi-static clips (pelvis within {QUASI_STATIC_REACH} m of its start): {len(qs)}; at tempo x1.00: "
                  f"{sum(r['tempo'] == 1.0 for r in qs)}/{len(qs)}; keypoint error vs kinematic-only: median "
                  f"{100 * np.median(loss):+.0f} %, worst {100 * loss.max():+.0f} % ({worst['clip']}); "
                  f"losing >= 20 %: {int((loss >= 0.2).sum())}")
    else:
        print(f"keypoint error: {kp.mean():.1f} mm; speed: {frames_total / cpu_new:,.0f} frames per CPU second")
    edges = [r["clip"] for r in ok if r["edge_only"]]
    print(f"violations confined to the first/last 2 frames: {len(edges)} clips" + (f" ({', '.join(edges[:5])})" if edges else ""))
    if not args.no_artefacts:
        ratios = np.array([r["fine_ratio"] for r in ok])
        print(f"100 fps vs native rate, peak root/joint acceleration ratio: median {np.median(ratios):.2f}, "
              f"max {ratios.max():.2f}; clips over 1.5x: {int((ratios > 1.5).sum())}")
        over = [r for r in ok if r["fine_ratio"] > 1.5]
        if over:
            samp = np.array([r["sampling"] for r in over])
            traj = np.array([r["trajectory"] for r in over])
            print(f"  of those, split as sampling (the native frames' own spline vs their second difference) x "
                  f"trajectory (100 fps result vs that spline): sampling median {np.median(samp):.2f}, max "
                  f"{samp.max():.2f}; trajectory median {np.median(traj):.2f}, max {traj.max():.2f}; "
                  f"{int((traj <= 1.5).sum())} of {len(over)} within 1.5x of their own spline")
    if args.csv:
        import csv
        with open(args.csv, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["clip", "feasible", "stays_up", "tempo", "legs", "kp_mm", "pose_mm", "kp_base_mm", "failed"])
            for r in ok:
                w.writerow([r["clip"], r["feasible"], r["stays_up"], r["tempo"], _legs(r), round(r["kp_mm"], 2),
                            round(r["pose_mm"], 2), round(r.get("kp_base_mm", float("nan")), 2), " ".join(r["failed"])])
    return 0


if __name__ == "__main__":
    sys.exit(main())

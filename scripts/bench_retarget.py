"""Benchmark and acceptance figures of the retargeter; prints every figure it measures.

    MENAGERIE_ROOT=/work/shared/menagerie python scripts/bench_retarget.py [--quick] [--robots op3,menagerie:unitree_g1]

1. compile time of the op3 problem (fresh cache directory), and of each robot's (cached if so);
2. speed on op3 with every constraint on: frames per CPU-second of this process (one core),
   solver only, after compilation, best of 3 runs over the HumanML3D clips and the demo;
3. the per-frame IPOPT baseline of the same costs on a subset, its speed, the ratio, and how
   close its answer is (mean keypoint error of both, mean |dq|);
4. reachable targets: keypoints from the robot's own FK along random smooth joint trajectories
   (within limits, lowest sole on the floor, clear of self-collision), retargeted with unit scale,
   no contacts/balance, tracking + temporal terms and a faint posture term (IK under joint and
   velocity limits): mean keypoint error by the solver and by the default (exact reach);
5. per clip of ../shared/motions that read_motion reads, for each robot: limit violations, worst
   sole depth, % of contact frames with sole speed <= 1 cm/s, worst self-collision depth (MuJoCo
   geoms), max joint speed / limit, CoM-in-shrunk-polygon % (quasi-static clips, balance on;
   the other clips are retargeted with balance off), smoothness: (joint, frame) velocity sign
   reversals with |v| > 1 rad/s on both sides and the peak joint acceleration (rad/s^2), and on
   the quasi-static clips the validator's verdicts (physics on: the failed checks are listed),
   then totals.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from motion2robot.errors import UserError
from motion2robot.motion import HumanMotion, read_motion
from motion2robot.motion.human import KP, SMPL22
from motion2robot.motion.ops import trim
from motion2robot.retarget import RetargetOptions, Weights, whole_body as retarget
from motion2robot.retarget import compiled as compiled_mod
from motion2robot.retarget import lanes
from motion2robot.retarget.contacts import HEEL_LIFT, contact_labels
from motion2robot.retarget.metrics import acceptance
from motion2robot.retarget.scale import Scale
from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate import CheckOptions, check

#: Clips meant to be quasi-static (standing, waving, reaching, bowing): balance on and judged.
QUASI_STATIC = ("M010968.npy", "bandai_byebye_normal_001.bvh", "bandai_bow_normal_001.bvh", "demo_wave_squat.npy")
MAX_AMPLITUDE = 0.5  # rad, reachable-target trajectories
POSTURE_REACHABLE = 1e-6  # posture weight of the reachable-target runs
SUFFIXES = (".npy", ".npz", ".bvh", ".pkl", ".pt", ".amc")


def shared_dir() -> Path:
    env = os.environ.get("MOTION2ROBOT_SHARED")
    return Path(env) if env else ROOT.parent / "shared"


def clips(shared: Path) -> list[tuple[str, HumanMotion]]:
    out = [("demo_wave_squat.npy", read_motion(ROOT / "motion2robot" / "data" / "demo_wave_squat.npy")[0])]
    for path in sorted((shared / "motions").rglob("*")):
        if not path.is_file() or path.suffix not in SUFFIXES or path.stem in ("Mean", "Std"):
            continue
        try:
            human = read_motion(path)
        except UserError as err:
            print(f"  (skipped {path.relative_to(shared)}: {err})")
            continue
        for i, h in enumerate(human[:3]):  # at most 3 samples of a multi-clip file
            out.append((f"{path.parent.name}/{path.name}" + (f"#{i}" if len(human) > 1 else ""), h))
    return out


def compile_time() -> None:
    robot = load_robot("op3")
    with tempfile.TemporaryDirectory() as tmp:
        old = os.environ.get("MOTION2ROBOT_CACHE")
        os.environ["MOTION2ROBOT_CACHE"] = tmp
        try:
            cp = compiled_mod.compiled_problem.__wrapped__(robot)
        finally:
            if old is None:
                os.environ.pop("MOTION2ROBOT_CACHE")
            else:
                os.environ["MOTION2ROBOT_CACHE"] = old
    flags = (*compiled_mod.LANE_CFLAGS, *lanes.isa()[1]) if cp.backend == "lanes" else compiled_mod.CFLAGS
    print(f"compile (op3, fresh cache): build casadi graph {cp.build_s:.2f} s, {cp.backend} backend "
          f"({lanes.isa()[0] if cp.backend == 'lanes' else 1} frames per operation), "
          f"gcc {' '.join(flags)} on {os.cpu_count()} cores {cp.compile_s:.1f} s")


def speed(robot, humans: list[HumanMotion]) -> float:
    retarget(humans[0], robot)  # compile / load the library, warm caches
    best = 0.0
    frames = sum(h.num_frames for h in humans)
    for _ in range(3):
        cpu = wall = 0.0
        for h in humans:
            c0 = time.process_time()
            m = retarget(h, robot)
            cpu += time.process_time() - c0
            wall += m.meta["solver"]["time_s"]
        best = max(best, frames / cpu)
        print(f"  run: {frames} frames, {cpu:.3f} CPU-s (whole retarget() call) -> {frames / cpu:.0f} frames/s/core; "
              f"solver wall {wall:.3f} s -> {frames / wall:.0f} frames/s")
    print(f"speed (op3, every constraint on, one process, after compilation): {best:.0f} frames per CPU-second")
    return best


def baseline(robot, human: HumanMotion, fast_fps: float) -> None:
    fast = retarget(human, robot)
    c0 = time.process_time()
    slow = retarget(human, robot, RetargetOptions(solver="ipopt"))
    cpu = time.process_time() - c0
    ipopt_fps = human.num_frames / cpu
    ef, es = (np.mean(m.meta["solver"]["residual_per_frame"]) for m in (fast, slow))
    dq = np.abs(fast.qpos[:, 7:] - slow.qpos[:, 7:]).mean()
    print(f"IPOPT baseline ({human.num_frames} frames of {Path(str(human.meta.get('source'))).name}): "
          f"{ipopt_fps:.1f} frames per CPU-second; fast/IPOPT = {fast_fps / ipopt_fps:.0f}x")
    of, os_ = (m.meta["solver"]["objective"]["total"] for m in (fast, slow))
    print(f"  same answer? objective (same costs, final trajectories) fast {of:.4f} vs IPOPT {os_:.4f}; "
          f"mean keypoint error fast {1000 * ef:.1f} mm vs IPOPT {1000 * es:.1f} mm; "
          f"mean |dq| {dq:.3f} rad; worst constraint residual fast {1000 * fast.meta['solver']['max_constraint_residual']:.3f} mm, "
          f"IPOPT {1000 * slow.meta['solver']['max_constraint_residual']:.3f} mm")
    same_problem(robot, human)


def same_problem(robot, human: HumanMotion) -> None:
    """Both solvers on the identical pinned-stage problem (the fast path's stage-2 inputs): the
    sum of frame objectives each reaches, and whether IPOPT's answer is a fixed point of the LM."""
    from motion2robot.retarget import baseline as baseline_mod
    from motion2robot.retarget import solver as solver_mod

    captured = []
    original = solver_mod.solve

    def spy(problem, params, q0, weights, iterations, lower, upper, *rest, **kw):
        captured.append((params.copy(), q0.copy(), weights, lower, upper))
        return original(problem, params, q0, weights, iterations, lower, upper, *rest, **kw)

    solver_mod.solve = spy
    try:
        retarget(human, robot)
    finally:
        solver_mod.solve = original
    params, q0, weights, lower, upper = captured[-1]
    cp = compiled_mod.compiled_problem(robot)
    wvec = np.array(weights.frame_vector())

    def per_frame(Q):
        return cp.cost_eval(len(Q))(Q, params, wvec)[0][:, 0]

    ipopt_q = baseline_mod.solve_ipopt(cp, params, q0, weights, 0, lower, upper)[0]
    line = []
    for it in (RetargetOptions().iterations[1], 10, 50, 200):
        line.append(f"LM {it} iterations {per_frame(original(cp, params, q0, weights, it, lower, upper)[0]).sum():.3f}")
    plain = [per_frame(original(cp, params, q0, weights, it, lower, upper, second_order=0)[0]).sum() for it in (10, 50)]
    stay = original(cp, params, ipopt_q, weights, 50, lower, upper)[0]
    far = per_frame(original(cp, params, q0, weights, 200, lower, upper)[0]) - per_frame(ipopt_q)
    print(f"  same problem (pinned stage, {len(q0)} frames; frame objectives summed): start {per_frame(q0).sum():.3f}; "
          f"{'; '.join(line)}; IPOPT {per_frame(ipopt_q).sum():.3f}")
    print(f"  without the second-order correction (LM steps judged off the constraints): 10 iterations {plain[0]:.3f}, "
          f"50 iterations {plain[1]:.3f}")
    # IPOPT solves frame after frame from the previous frame's answer: the same start for the LM
    # (no temporal terms)
    still = replace(weights, velocity=0.0, acceleration=0.0)
    seq = q0.copy()
    for t in range(len(seq)):
        seq[t:t + 1] = original(cp, params[t:t + 1], seq[t - 1:t] if t else q0[:1], still, 50, lower, upper)[0]
    print(f"  LM started at IPOPT's answer: {per_frame(stay).sum():.3f} after 50 iterations; "
          f"after 200 iterations from the start the LM is above IPOPT by > 0.1 in {int((far > 0.1).sum())} frames; "
          f"frame by frame from the previous frame's answer, as IPOPT starts, 50 iterations each: {per_frame(seq).sum():.3f}")


def _collision_free(points, q: np.ndarray) -> bool:
    """Every frame of ``q`` clear of self-collision under the solver's capsules (gaps >= 0)."""
    gaps = np.asarray(points(q)[3])
    return gaps.size == 0 or float(gaps.min()) >= 0.0


def reachable(robot, seeds: int = 3, T: int = 40, fps: float = 20.0, amplitude: float = 0.15) -> float:
    """Mean keypoint error (m) of the retargeting of the robot's own keypoints along random smooth
    joint trajectories that satisfy every hard constraint (joint limits, a sole on the floor, no
    self-collision under the solver's capsules: a trajectory through the capsules is not reachable,
    and the joint smoothing's collision pushes rightly move it; such a seed's amplitude is halved
    until it is clear, up to 4 times). Printed for the solver (the exact reach off) and for the
    default pipeline (a robot-shaped motion reached pose by pose)."""
    cp = compiled_mod.compiled_problem(robot)
    points = cp.points_eval(T)
    # IK: tracking terms, a faint posture term and the temporal terms (they pick one solution in
    # the null space of redundant robots, else frames wander apart and the velocity limit bites);
    # no floor/self-collision terms or corrections; joint and velocity limits kept
    zero = {k: 0.0 for k in ("pelvis_heading", "torso_up", "foot_heading", "sole_flat", "floor", "self_collision")}
    zero["posture"] = POSTURE_REACHABLE
    errs: dict[bool, list[float]] = {False: [], True: []}
    used: list[float] = []
    seed = -1
    while len(used) < seeds and seed < 30:
        seed += 1
        rng = np.random.default_rng(seed)
        t = np.arange(T) / fps
        span = robot.upper - robot.lower
        shape = np.sin(2 * np.pi * rng.uniform(0.1, 0.25, robot.n_joints) * t[:, None] + rng.uniform(0, 6.3, robot.n_joints))
        for halvings in range(5):
            amp = amplitude / 2 ** halvings
            hinges = np.clip(robot.nominal_qpos[7:] + np.minimum(amp * span, MAX_AMPLITUDE) * shape, robot.lower, robot.upper)
            q = np.tile(robot.nominal_qpos, (T, 1))
            q[:, 7:] = hinges
            if _collision_free(points, q):
                break
        else:
            continue
        q[:, 2] -= points(q)[1].reshape(T, -1, 3)[..., 2].min(axis=1)
        kp = points(q)[0].reshape(T, -1, 3)
        pos = np.repeat(kp[:, [robot.keypoints.index("pelvis")]], len(SMPL22), axis=1)
        for i, name in enumerate(robot.keypoints):
            pos[:, KP[name]] = kp[:, i]
        used.append(amp)
        for reach in (False, True):
            out = retarget(HumanMotion(pos, fps, meta={"source": "fk"}), robot,
                           RetargetOptions(balance=False, contacts=False, scale=Scale(1.0, 1.0, 1.0), tempo="human",
                                           legs="whole", reach=reach, weights=Weights(**zero), iterations=(40, 10),
                                           corrections=0))
            errs[reach].append(float(np.mean(out.meta["solver"]["residual_per_frame"])))
    solver = float(np.mean(errs[False])) if used else float("nan")
    exact = float(np.mean(errs[True])) if used else float("nan")
    print(f"reachable targets ({robot.name}, {len(used)} random smooth collision-free trajectories x {T} frames, "
          f"hinges nominal +- min(k x range, {MAX_AMPLITUDE} rad), k = {', '.join(f'{a:g}' for a in used)}, "
          f"{seed + 1} drawn): mean keypoint error {1000 * solver:.4f} mm by the solver, "
          f"{1000 * exact:.4f} mm by the default pipeline (exact reach)")
    return solver


def table(robot, items: list[tuple[str, HumanMotion]]) -> None:
    print(f"\nacceptance on {robot.name} ({len(items)} clips)")
    head = (f"{'clip':44s} {'frames':>6s} {'bal':>3s} {'limits':>6s} {'depth mm':>8s} {'slow %':>7s} {'coll mm':>7s} {'v/vmax':>6s} "
            f"{'CoM in %':>8s} {'kp mm':>6s} {'revers':>6s} {'acc/s2':>7s} check (quasi-static)")
    print(head)
    tot = {"frames": 0, "limits": 0, "depth": 0.0, "contact": 0, "slow": 0.0, "coll": 0.0, "speed": 0.0, "com_bad": 0,
           "reversals": 0, "acc": 0.0, "acc_fail": 0, "heel_up": 0, "human_contact": 0, "human_slow": 0.0}
    for name, h in items:
        quasi = Path(name.split("#")[0]).name in QUASI_STATIC
        try:
            m = retarget(h, robot, RetargetOptions(balance=quasi))
        except UserError as err:
            print(f"{name[:44]:44s} refused: {err}")
            continue
        a = acceptance(m, robot)
        com = f"{a['com_inside_pct']:8.1f}" if quasi else f"{'-':>8s}"
        kp = 1000 * np.mean(m.meta["solver"]["residual_per_frame"])
        verdict = ""
        if quasi:
            rep = check(m, robot, CheckOptions(physics=True))
            failed = [k for k, c in rep.checks.items() if not c.get("ok", True)]
            verdict = "FEASIBLE" if rep.feasible else "fails " + ",".join(failed)
            tot["acc_fail"] += int(not rep.checks["acceleration"]["ok"])
        print(f"{name[:44]:44s} {a['frames']:6d} {'on' if quasi else 'off':>3s} {a['limit_violations']:6d} {a['sole_depth_mm']:8.2f} "
              f"{a['contact_slow_pct']:7.1f} {a['self_collision_mm']:7.2f} {a['speed_ratio']:6.3f} {com} {kp:6.1f} "
              f"{a['reversals']:6d} {a['peak_acceleration']:7.1f} {verdict}", flush=True)
        tot["reversals"] += a["reversals"]
        tot["acc"] = max(tot["acc"], a["peak_acceleration"])
        tot["frames"] += a["frames"]
        tot["limits"] += a["limit_violations"]
        tot["depth"] = max(tot["depth"], a["sole_depth_mm"])
        tot["contact"] += a["contact_frames"]
        tot["slow"] += a["contact_slow_pct"] / 100 * a["contact_frames"]
        tot["heel_up"] += m.meta.get("contact_frames_heel_up", 0)
        # the same figure over the human's own labels (frames on the toes with the heel up included)
        human_labels = contact_labels(h)[0].astype(int).tolist()
        ah = acceptance(RobotMotion(m.qpos, m.fps, m.joint_names, m.robot, {**m.meta, "contacts": human_labels}),
                        robot, collisions=False)
        tot["human_contact"] += ah["contact_frames"]
        tot["human_slow"] += ah["contact_slow_pct"] / 100 * ah["contact_frames"]
        tot["coll"] = max(tot["coll"], a["self_collision_mm"])
        tot["speed"] = max(tot["speed"], a["speed_ratio"])
        if quasi:
            tot["com_bad"] += int(a["com_inside_pct"] < 100.0)
    slow = 100 * tot["slow"] / max(tot["contact"], 1)
    print(f"{'TOTAL':44s} {tot['frames']:6d} {'':>3s} {tot['limits']:6d} {tot['depth']:8.2f} {slow:7.1f} {tot['coll']:7.2f} {tot['speed']:6.3f} "
          f"{'quasi-static clips with CoM outside: ' + str(tot['com_bad'])}")
    print(f"{'':44s} velocity reversals (|v| > 1 rad/s) in total: {tot['reversals']}; peak acceleration {tot['acc']:.1f} rad/s^2; "
          f"quasi-static clips failing the acceleration check: {tot['acc_fail']}")
    human = 100 * tot["human_slow"] / max(tot["human_contact"], 1)
    print(f"{'':44s} contact frames judged (planted): {tot['contact']}; human contact frames with the heel more than "
          f"{100 * HEEL_LIFT:.0f} cm up, not planted: {tot['heel_up']}; over the human's own labels: {human:.1f} % slow")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robots", default="op3,menagerie:unitree_g1")
    ap.add_argument("--quick", action="store_true", help="skip the fresh compile and use fewer clips")
    ap.add_argument("--parts", default="compile,speed,baseline,reachable,table",
                    help="comma-separated subset of compile,speed,baseline,reachable,table")
    args = ap.parse_args()
    parts = set(args.parts.split(","))
    warnings.filterwarnings("ignore")
    shared = shared_dir()
    if not (shared / "motions").is_dir():
        print(f"no motions folder under {shared}; set MOTION2ROBOT_SHARED")
        return 2
    if not args.quick and "compile" in parts:
        compile_time()
    op3 = load_robot("op3")
    hml = [read_motion(p)[0] for p in sorted((shared / "motions" / "humanml3d_joints").glob("*.npy"))
           if "raw" not in p.name]
    hml.append(read_motion(ROOT / "motion2robot" / "data" / "demo_wave_squat.npy")[0])
    fast_fps = speed(op3, hml) if "speed" in parts else float("nan")
    if "baseline" in parts:
        baseline(op3, trim(hml[-2], 0, 40), fast_fps)
    items = clips(shared)
    if args.quick:
        items = items[::3]
    for name in args.robots.split(","):
        robot = load_robot(name)
        cp = compiled_mod.compiled_problem(robot)
        print(f"\n{robot.name}: {robot.n_joints} joints; problem built in {cp.build_s:.2f} s, "
              f"compiled in {cp.compile_s:.1f} s{' (from cache)' if cp.cached else ''}")
        if "reachable" in parts:
            reachable(robot)
        if "table" in parts:
            table(robot, items)
    return 0


if __name__ == "__main__":
    sys.exit(main())

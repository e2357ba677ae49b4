"""Where the CPU time of the default ``retarget()`` goes: per stage, per check part, per attempt.

Over the readable clips of ``../shared/motions`` (or ``--clips`` indices of them), runs the
default retarget (tempo/legs policy, attempts judged by ``check``) with every stage of
``whole_body``, the judge's parts and the physics playback timed in CPU seconds
(``time.process_time``), and prints per clip the attempts taken, then the totals: frames per CPU
second, each stage's share, the solves and checks of the returned attempt vs the others, the
playback of the returned attempts alone (the floor no policy change removes) and the retargeting
stages of the returned attempts alone (what one attempt at a known tempo and legs costs).

Run:  python scripts/profile_retarget.py [--robot op3] [--limit N] [--clips 2,7,31]
"""

from __future__ import annotations

import collections
import sys
import time

import numpy as np

import motion2robot.retarget.api as rapi
import motion2robot.retarget.executable as ex
import motion2robot.retarget.gait as gait
import motion2robot.retarget.leg_tracker as leg_tracker
import motion2robot.validate as vpkg
import motion2robot.validate.api as vapi
import motion2robot.validate.context as vctx
from _clips import clips_parser, motions_missing, readable_clips
from motion2robot.robot import load_robot

CPU: dict[str, float] = collections.defaultdict(float)
CALLS: dict[str, int] = collections.defaultdict(int)
#: (qpos, CPU s) of each whole-body solve, check and playback of the clip being retargeted.
RUNS: dict[str, list] = {"solve": [], "check": [], "play": []}


def timed(module, name: str, key: str, record: str | None = None) -> None:
    """Replace ``module.name`` by a wrapper adding its CPU time to ``CPU[key]`` (and, with
    ``record``, the motion it made or judged to ``RUNS[record]``)."""
    f = getattr(module, name)

    def wrapper(*args, **kwargs):
        c = time.process_time()
        out = f(*args, **kwargs)
        dt = time.process_time() - c
        CPU[key] += dt
        CALLS[key] += 1
        if record == "solve":
            RUNS[record].append((out.qpos, dt))
        elif record == "check":
            RUNS[record].append((args[0].qpos, dt))
        elif record == "play":
            RUNS[record].append((args[0].motion.qpos, dt))
        return out

    setattr(module, name, wrapper)


def instrument() -> None:
    for n in ("prepare", "free_solve", "plan_contacts", "pinned_solve", "servo_rounds", "joint_smoothing",
              "dynamic_balance", "root_shift", "robot_motion"):
        timed(rapi, n, f"retarget: {n}")
    timed(rapi, "whole_body", "retarget: whole_body (all stages)", "solve")
    timed(rapi, "steps", "retarget: steps pattern (all stages)", "solve")
    timed(gait, "walk_pattern", "retarget: steps: walk pattern (CoM plan, leg tracking)")
    timed(leg_tracker.LegTracker, "solve", "retarget: steps: leg tracker")
    timed(ex, "stretch", "policy: tempo stretch")
    timed(rapi, "stance", "policy: stance rewrite")
    timed(vctx, "compute_kinematics", "check: per-frame MuJoCo pass")
    timed(vctx, "inverse_dynamics", "check: inverse dynamics")
    timed(vapi, "kinematic_checks", "check: kinematic checks")
    timed(vapi, "play", "check: physics playback", "play")
    timed(vapi, "rollout", "check: rollout verdict")
    timed(vapi, "check", "check (all parts)", "check")
    vpkg.check = vapi.check  # the policy's judge imports it from the package


def main() -> int:
    ap = clips_parser(__doc__)
    ap.add_argument("--clips", default=None, help="comma-separated indices of the readable clips")
    args = ap.parse_args()
    if motions_missing(args.motions):
        return 2
    robot = load_robot(args.robot)
    clips = list(readable_clips(args.motions, args.limit, args.only))
    if args.clips:
        clips = [clips[int(i)] for i in args.clips.split(",")]
    rapi.retarget(clips[0][1], robot)  # compile/load outside the timing
    instrument()
    role: dict[str, float] = collections.defaultdict(float)
    total = frames = floor = 0.0
    for name, human in clips:
        for runs in RUNS.values():
            runs.clear()
        c = time.process_time()
        motion = rapi.retarget(human, robot)
        dt = time.process_time() - c
        total += dt
        frames += human.num_frames
        for kind, runs in RUNS.items():
            for qpos, cpu in runs:
                mine = qpos.shape == motion.qpos.shape and np.array_equal(qpos, motion.qpos)
                role[f"{kind}, {'returned attempt' if mine else 'other attempts'}"] += cpu
        attempts = " -> ".join(f"{a['legs']} x{a['tempo']:g}" + ("" if a["feasible"] else f" ({','.join(a['failed']) or 'rollout'})")
                               for a in motion.meta["attempts"])
        print(f"  {name:44s} T={human.num_frames:5d} {dt:6.2f} CPU s {human.num_frames / dt:6.0f} frames/s  {attempts}",
              flush=True)
    floor = role["play, returned attempt"]
    print(f"\n{robot.name}: {len(clips)} clips, {int(frames)} frames, {total:.2f} CPU s = {frames / total:,.0f} frames per CPU "
          f"second; {CALLS['retarget: whole_body (all stages)']} whole-body solves, {CALLS['check (all parts)']} checks, "
          f"{CALLS['check: physics playback']} playbacks")
    for key, v in sorted(CPU.items(), key=lambda kv: -kv[1]):
        print(f"  {key:40s} {v:8.2f} s {100 * v / total:5.1f} %  ({CALLS[key]} calls)")
    for key in sorted(role):
        print(f"  {key:40s} {role[key]:8.2f} s {100 * role[key] / total:5.1f} %")
    if floor:
        print(f"playback of the returned attempts alone: {1e6 * floor / frames:.0f} us per input frame "
              f"(at most {frames / floor:,.0f} frames per CPU second if nothing else cost anything)")
    solved = role["solve, returned attempt"]
    if solved:
        print(f"the retargeting stages of the returned attempts alone (at their tempo and legs, no judging, no "
              f"other attempt): {frames / solved:,.0f} frames per CPU second")
    return 0


if __name__ == "__main__":
    sys.exit(main())

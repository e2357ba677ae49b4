"""Physics playback: the robot on the floor, its servos driven exactly as ``stream`` drives them.

The robot starts standing at the first frame's pose (at rest) with its servos holding that pose
for ``settle_time``; then the servos get, tick by tick at ``stream_rate``, the goals ``stream``
would send (:mod:`~motion2robot.hardware.goals`: the motion sampled at the tick times, turned into
servo ticks by the same :class:`~motion2robot.hardware.guard.SafetyGuard`, i.e. rounded to whole
ticks, clipped to the joint limits and limited to the velocity limit's step per tick, after the
guard's ramp-in), each goal held until the next tick. The targets are the planned angles, plus
the predicted servo sag with ``sag_compensation`` (:mod:`~motion2robot.validate.sag`). The servo
model is :func:`~motion2robot.validate.models.physics_model` (gain ``kp``, torque limit). Every
motion frame records the joint angles, the torso pose and the floor contacts.

Fall: the torso (``robot.torso_body``) drops below ``fall_height_ratio`` times the REFERENCE
torso height at the same time, or tilts more than ``fall_tilt_deg`` away from the reference
torso's orientation (judging against the reference, not the start, keeps motions that sit down or
bow on purpose from counting as falls). Tracking error: simulated minus reference joint angle
over the frames before a fall.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import mujoco
import numpy as np

from motion2robot.hardware.calibration import Calibration
from motion2robot.hardware.goals import GoalSequence, goal_sequence
from motion2robot.hardware.guard import SafetyGuard
from motion2robot.hardware.limits import JointLimits
from motion2robot.hardware.policy import TorquePolicy
from motion2robot.robot.robot import Robot
from motion2robot.robot.servo_map import ServoMap, ServoSpec
from motion2robot.validate.context import Context
from motion2robot.validate.models import body_name, floor_geom, physics_model
from motion2robot.validate.sag import servo_targets

#: Seconds simulated after a fall before the playback stops.
AFTER_FALL = 0.5
#: Contact events listed in the report (counts cover all of them).
MAX_EVENTS = 40
#: The nominal servo of robots without a servo map: 4096 ticks per turn (Dynamixel X series).
NOMINAL_TICKS = 4096
NOMINAL_BAUD = 1_000_000


@dataclass(frozen=True, eq=False)
class Playback:
    """time (F,) s of the recorded motion frames; qpos (F, nq) simulated state (NaN after the
    playback stopped); q (F, n) its joint angles; torso_height
    (F,) m; tilt_deg (F,) angle between simulated and reference torso z axes;
    foot_contact (F, 2) bool; other_contact (F, nbody) bool non-foot bodies on the floor;
    realtime_factor: simulated / wall-clock seconds; goals (K, n) rad the servos were sent, one
    row per control tick at ``goal_rate`` Hz from the start of the settling, ``joint_names`` order
    (``goal_ticks`` of them are the settling and the guard's ramp-in, the rest play the motion)."""

    time: np.ndarray
    qpos: np.ndarray
    torso_height: np.ndarray
    tilt_deg: np.ndarray
    foot_contact: np.ndarray
    other_contact: np.ndarray
    realtime_factor: float
    fall_frame: int | None
    fall_cause: str | None
    goals: np.ndarray
    goal_rate: float
    goal_ticks: int

    @property
    def q(self) -> np.ndarray:
        return self.qpos[:, 7:]


def servo_calibration(robot: Robot) -> Calibration:
    """The calibration ``stream`` would use for ``robot``: its servo map (zero offsets do not
    change the angles a goal stands for); a robot without one, or whose map leaves hinges out,
    gets a nominal 4096-tick servo on every hinge."""
    servos = robot.config.servos
    if servos is None or {s.joint for s in servos.servos} != set(robot.joint_names):
        servos = ServoMap("nominal", NOMINAL_BAUD, NOMINAL_TICKS, NOMINAL_TICKS // 2,
                          tuple(ServoSpec(j, i + 1) for i, j in enumerate(robot.joint_names)))
    return Calibration.from_servo_map(servos)


def rollout_goals(ctx: Context) -> tuple[GoalSequence, Calibration]:
    """The goals ``stream`` would send for ``ctx.motion`` at ``options.stream_rate`` (the servos
    standing at its first frame, default torque policy's ramp speed), with the targets of
    :func:`~motion2robot.validate.sag.servo_targets` (sag-compensated with
    ``options.sag_compensation``), and the calibration that turns them into radians."""
    robot, opts = ctx.robot, ctx.options
    cal = servo_calibration(robot)
    guard = SafetyGuard(JointLimits.from_robot(robot).select(cal.joints), cal, opts.stream_rate,
                        TorquePolicy().ramp_speed)
    order = [robot.joint_index(j) for j in cal.joints]
    traj = servo_targets(ctx, opts.sag_compensation)[:, order]
    lo, hi = np.asarray(robot.lower)[order], np.asarray(robot.upper)[order]
    present = np.rint(cal.ticks_float(np.clip(ctx.kin.qpos[0, 7:][order], lo, hi)))
    return goal_sequence(guard, traj, ctx.kin.fps, opts.stream_rate, present), cal


def play(ctx: Context) -> Playback:
    """Run the physics playback of ``ctx.motion`` (see the module docstring)."""
    robot, opts, kin = ctx.robot, ctx.options, ctx.kin
    m = physics_model(robot, opts.timestep)
    d = mujoco.MjData(m)
    dt = m.opt.timestep
    seq, cal = rollout_goals(ctx)
    settle = round(opts.settle_time * opts.stream_rate)
    ticks = np.concatenate([np.repeat(seq.start[None], settle, axis=0), seq.ticks])
    ctrl_ticks = np.empty((ticks.shape[0], robot.n_joints))
    ctrl_ticks[:, [robot.joint_index(j) for j in cal.joints]] = cal.to_radians(ticks)
    steps = int(np.ceil(ticks.shape[0] / opts.stream_rate / dt - 1e-9))
    tick_of_step = np.minimum((np.arange(steps) * dt * opts.stream_rate + 1e-9).astype(int), ticks.shape[0] - 1)
    play_start = (settle + seq.ramp.shape[0]) / opts.stream_rate  # s of simulated time at play tick 0
    record_at = np.round((play_start + np.arange(kin.num_frames) / kin.fps) / dt).astype(int)
    record_at = np.minimum(record_at, steps - 1).tolist() + [-1]
    d.qpos[:] = kin.qpos[0]
    mujoco.mj_forward(m, d)

    F = kin.num_frames
    qpos = np.full((F, m.nq), np.nan)
    height = np.full(F, np.nan)
    tilt = np.full(F, np.nan)
    foot_contact = np.zeros((F, 2), dtype=bool)
    other = np.zeros((F, m.nbody), dtype=bool)
    floor = floor_geom(m)
    feet = np.asarray(robot.foot_bodies)
    torso = int(robot.torso_body)
    cos_tilt = np.cos(np.radians(opts.fall_tilt_deg))
    fall_frame, cause, stop_step = None, None, steps
    f, next_record = 0, record_at[0]
    d_ctrl, step = d.ctrl, mujoco.mj_step
    # the goal is constant between control ticks: step in runs (mj_step's nstep, the same steps in
    # C) that stop at every tick change, every recorded frame and the stop after a fall
    bounds = sorted({0, stop_step, *(np.flatnonzero(np.diff(tick_of_step)) + 1).tolist(), *record_at[:-1]})
    t0 = time.perf_counter()
    for i, s in enumerate(bounds):
        if s >= stop_step:
            break
        if s == next_record:
            qpos[f] = d.qpos
            height[f] = d.xpos[torso, 2]
            up = d.xmat[torso, [2, 5, 8]]
            c = float(np.clip(up @ kin.torso_up[f], -1.0, 1.0))
            tilt[f] = np.degrees(np.arccos(c))
            n = d.ncon
            if n:
                g = d.contact.geom[:n]
                on = (g == floor).any(axis=1)
                bodies = m.geom_bodyid[np.where(g[:, 0] == floor, g[:, 1], g[:, 0])[on]]
                foot_contact[f] = [bool((bodies == b).any()) for b in feet]
                other[f, bodies] = True
                other[f, feet] = False
            if fall_frame is None:
                if height[f] < opts.fall_height_ratio * kin.torso_pos[f, 2]:
                    fall_frame, cause = f, "height"
                elif c < cos_tilt:
                    fall_frame, cause = f, "tilt"
                if fall_frame is not None:
                    stop_step = min(stop_step, s + round(AFTER_FALL / dt))
            f += 1
            next_record = record_at[f]
        d_ctrl[:] = ctrl_ticks[tick_of_step[s]]
        step(m, d, min(bounds[i + 1], stop_step) - s)
    wall = time.perf_counter() - t0
    sim_time = min(stop_step, steps) * dt
    return Playback(time=np.arange(F) / kin.fps, qpos=qpos, torso_height=height, tilt_deg=tilt,
                    foot_contact=foot_contact, other_contact=other,
                    realtime_factor=sim_time / wall if wall > 0 else float("inf"),
                    fall_frame=fall_frame, fall_cause=cause, goals=ctrl_ticks, goal_rate=float(opts.stream_rate),
                    goal_ticks=settle + seq.ramp.shape[0])


def contact_events(pb: Playback, ctx: Context) -> list[dict]:
    """Foot touchdowns/liftoffs and other bodies touching the floor, in time order."""
    m = physics_model(ctx.robot, ctx.options.timestep)
    recorded = ~np.isnan(pb.torso_height)
    fc, oc = pb.foot_contact[recorded], pb.other_contact[recorded]
    events = []
    for k, side in enumerate(("left", "right")):
        ch = np.flatnonzero(np.diff(fc[:, k].astype(int)))
        for i in ch:
            events.append({"time_s": round(float(pb.time[i + 1]), 3), "event": "touchdown" if fc[i + 1, k] else "liftoff",
                           "body": f"{side} foot"})
    began = oc & ~np.vstack([np.zeros((1, oc.shape[1]), dtype=bool), oc[:-1]])
    for fr, b in zip(*np.nonzero(began)):
        events.append({"time_s": round(float(pb.time[fr]), 3), "event": "floor contact", "body": body_name(m, b)})
    return sorted(events, key=lambda e: e["time_s"])


def rollout(ctx: Context, pb: Playback | None = None) -> dict:
    """The playback's verdict: fell or not, with the time; tracking error; contact events."""
    pb = play(ctx) if pb is None else pb
    names = ctx.robot.joint_names
    end = pb.fall_frame if pb.fall_frame is not None else len(pb.time)
    err = pb.q[:end] - ctx.kin.qpos[:end, 7:]
    err = err[~np.isnan(err).any(axis=1)]
    rms = np.sqrt((err ** 2).mean(axis=0)) if len(err) else np.zeros(len(names))
    mx = np.abs(err).max(axis=0) if len(err) else np.zeros(len(names))
    events = contact_events(pb, ctx)
    fell = pb.fall_frame is not None
    played = ~np.isnan(pb.qpos).any(axis=1)
    drift = np.linalg.norm(pb.qpos[played, :2] - ctx.kin.qpos[played, :2], axis=1)
    return {
        "ok": not fell, "frames": list(range(pb.fall_frame, len(pb.time))) if fell else [],
        "fell": fell, "fall_time_s": round(float(pb.time[pb.fall_frame]), 3) if fell else None,
        "fall_cause": pb.fall_cause,
        "tracking_rms_rad": {n: round(float(v), 4) for n, v in zip(names, rms)},
        "tracking_max_rad": {n: round(float(v), 4) for n, v in zip(names, mx)},
        "tracking_rms_mean_rad": round(float(rms.mean()), 4),
        "worst_tracking_joint": names[int(np.argmax(mx))] if len(names) else None,
        "root_drift_max_m": round(float(drift.max()), 4) if drift.size else 0.0,
        "contact_events": events[:MAX_EVENTS], "n_contact_events": len(events),
        "n_floor_contacts_other": sum(e["event"] == "floor contact" for e in events),
        "timestep_s": ctx.options.timestep, "stream_rate_hz": ctx.options.stream_rate,
        "sag_compensation": ctx.options.sag_compensation, "realtime_factor": round(pb.realtime_factor, 1),
    }

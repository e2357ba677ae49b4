"""Physics playback: the robot on the floor, servo-like position actuators fed the trajectory.

The robot starts at the first frame's pose (at rest), holds it for ``settle_time``, then its
actuators (see :func:`~motion2robot.validate.models.physics_model`: gain ``kp``, torque limit)
receive the joint angles linearly interpolated at the motion's rate, each goal rate-limited per
step to the servo's velocity limit. Every motion frame records the joint angles, the torso pose
and the floor contacts.

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

from motion2robot.validate.context import Context
from motion2robot.validate.models import body_name, floor_geom, physics_model

#: Seconds simulated after a fall before the playback stops.
AFTER_FALL = 0.5
#: Contact events listed in the report (counts cover all of them).
MAX_EVENTS = 40


@dataclass(frozen=True, eq=False)
class Playback:
    """time (F,) s of the recorded motion frames; qpos (F, nq) simulated state (NaN after the
    playback stopped); q (F, n) its joint angles; torso_height
    (F,) m; tilt_deg (F,) angle between simulated and reference torso z axes;
    foot_contact (F, 2) bool; other_contact (F, nbody) bool non-foot bodies on the floor;
    realtime_factor: simulated / wall-clock seconds."""

    time: np.ndarray
    qpos: np.ndarray
    torso_height: np.ndarray
    tilt_deg: np.ndarray
    foot_contact: np.ndarray
    other_contact: np.ndarray
    realtime_factor: float
    fall_frame: int | None
    fall_cause: str | None

    @property
    def q(self) -> np.ndarray:
        return self.qpos[:, 7:]


def goals(reference: np.ndarray, fps: float, dt: float, vmax: np.ndarray, lower: np.ndarray,
          upper: np.ndarray, settle_steps: int) -> np.ndarray:
    """Per-step actuator goals (S, n): ``settle_steps`` of frame 0, then the reference linearly
    interpolated at the step times, clipped to the range and rate-limited to ``vmax`` (rad/s)."""
    T = reference.shape[0]
    steps = round((T - 1) / fps / dt) + 1
    t = np.arange(steps) * dt * fps  # in frames
    i0 = np.minimum(np.floor(t).astype(int), T - 1)
    i1 = np.minimum(i0 + 1, T - 1)
    w = (t - i0)[:, None]
    target = np.clip((1 - w) * reference[i0] + w * reference[i1], lower, upper)
    target = np.concatenate([np.repeat(target[:1], settle_steps, axis=0), target])
    step = vmax * dt
    out = np.empty_like(target)
    cur = target[0].copy()
    for s in range(target.shape[0]):
        cur += np.clip(target[s] - cur, -step, step)
        out[s] = cur
    return out


def play(ctx: Context) -> Playback:
    """Run the physics playback of ``ctx.motion`` (see the module docstring)."""
    robot, opts, kin = ctx.robot, ctx.options, ctx.kin
    m = physics_model(robot, opts.timestep)
    d = mujoco.MjData(m)
    dt = m.opt.timestep
    ref = kin.qpos[:, 7:]
    settle = round(opts.settle_time / dt)
    ctrl = goals(ref, kin.fps, dt, np.asarray(robot.velocity_limit), np.asarray(robot.lower),
                 np.asarray(robot.upper), settle)
    per_frame = 1.0 / (kin.fps * dt)
    record_at = (settle + np.round(np.arange(kin.num_frames) * per_frame).astype(int)).tolist() + [-1]
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
    fall_frame, cause, stop_step = None, None, ctrl.shape[0]
    f, next_record = 0, record_at[0]
    d_ctrl, step = d.ctrl, mujoco.mj_step
    t0 = time.perf_counter()
    for s in range(ctrl.shape[0]):
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
        d_ctrl[:] = ctrl[s]
        step(m, d)
    wall = time.perf_counter() - t0
    sim_time = min(stop_step, ctrl.shape[0]) * dt
    return Playback(time=np.arange(F) / kin.fps, qpos=qpos, torso_height=height, tilt_deg=tilt,
                    foot_contact=foot_contact, other_contact=other,
                    realtime_factor=sim_time / wall if wall > 0 else float("inf"),
                    fall_frame=fall_frame, fall_cause=cause)


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
        "timestep_s": ctx.options.timestep, "realtime_factor": round(pb.realtime_factor, 1),
    }

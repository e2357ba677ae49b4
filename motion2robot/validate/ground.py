"""The floor: geoms (and sole corners) below it, and feet skating on it.

- penetration: any robot geom deeper than ``ground_depth`` into the floor (from the contacts of
  the check model), or a sole corner lower than ``-ground_depth`` (a foot's geoms and its sole
  corners are reported together as "left foot" / "right foot");
- skating: a foot in contact moving horizontally faster than ``skate_speed`` for at least
  ``min_run`` frames. "In contact" is the motion's contact label (retargeted motions carry the
  labels they were solved with) AND a sole corner within ``contact_height`` of the floor; without
  labels, any corner that low counts. A swing foot passing low over the floor without a contact
  label is not skating: it is reported as ``low_swing_frames`` (a scuff risk, figures only);
- non-foot contacts (figures only): bodies other than the feet touching the floor.
"""

from __future__ import annotations

import numpy as np

from motion2robot.validate.context import Context
from motion2robot.validate.frames import frame_list, keep_runs
from motion2robot.validate.models import body_name, floor_geom

SIDES = ("left", "right")


def ground(ctx: Context) -> dict:
    """Penetration and skating verdict, with the non-foot contacts as figures."""
    m, c, opts = ctx.kin.model, ctx.kin.contacts, ctx.options
    T = ctx.kin.num_frames
    floor = floor_geom(m)
    on_floor = (c.geom1 == floor) | (c.geom2 == floor)
    other = np.where(c.geom1 == floor, c.geom2, c.geom1)
    body = m.geom_bodyid[other]
    deep = on_floor & (c.dist < -opts.ground_depth)
    feet = [int(b) for b in np.asarray(ctx.robot.foot_bodies)]
    corner_z = ctx.kin.corners[..., 2]  # (T, 2, 4)
    found: dict[str, tuple[float, int, set]] = {}  # name -> (depth, worst frame, frames)

    def add(name: str, depth: np.ndarray, frames: np.ndarray) -> None:
        k = int(np.argmax(depth))
        old = found.get(name, (0.0, -1, set()))
        worst = (float(depth[k]), int(frames[k])) if depth[k] > old[0] else old[:2]
        found[name] = (worst[0], worst[1], old[2] | {int(f) for f in frames})

    for b in np.unique(body[deep]):
        sel = deep & (body == b)
        name = f"{SIDES[feet.index(int(b))]} foot" if int(b) in feet else body_name(m, b)
        add(name, -c.dist[sel], c.frame[sel])
    for k, side in enumerate(SIDES):
        low_z = corner_z[:, k].min(axis=1)
        rows = np.flatnonzero(low_z < -opts.ground_depth)
        if rows.size:
            add(f"{side} foot", -low_z[rows], rows)
    pen = sorted(({"body": n, "depth_m": round(v[0], 4), "worst_frame": v[1], "frames": sorted(v[2])}
                  for n, v in found.items()), key=lambda v: -v["depth_m"])
    pen_frames = np.zeros(T, dtype=bool)
    pen_frames[c.frame[deep]] = True
    pen_frames |= corner_z.min(axis=(1, 2)) < -opts.ground_depth

    speed = np.linalg.norm(ctx.kin.corner_vel[..., :2], axis=-1)  # (T, 2, 4)
    fast_low = ctx.low & (speed > opts.skate_speed)
    if ctx.labels is None:
        in_contact = fast_low
    else:
        # While labelled in contact, the speed is measured between contact frames only: the
        # central difference at a touchdown or lift-off frame mixes in the swing.
        speed = np.where(ctx.labels[:, :, None], _contact_speed(ctx.kin.corners, ctx.labels, ctx.motion.fps), speed)
        in_contact = ctx.low & (speed > opts.skate_speed) & ctx.labels[:, :, None]
    sliding = keep_runs(in_contact.any(axis=2), opts.min_run)  # (T, 2)
    low_swing = keep_runs((fast_low & ~in_contact).any(axis=2), opts.min_run)
    if ctx.labels is not None:
        low_swing &= ~ctx.labels
    skating = []
    for k, side in enumerate(SIDES):
        if sliding[:, k].any():
            rows = np.flatnonzero(sliding[:, k])
            foot_speed = np.where(ctx.low[rows, k], speed[rows, k], 0.0).max(axis=1)
            skating.append({"foot": side, "speed_m_s": round(float(foot_speed.max()), 3),
                            "worst_frame": int(rows[np.argmax(foot_speed)]), "frames": [int(r) for r in rows]})

    touching = on_floor & (c.dist < 1e-3) & ~np.isin(body, feet)
    non_foot = [{"body": body_name(m, b), "frames": sorted({int(f) for f in c.frame[touching & (body == b)]})}
                for b in np.unique(body[touching])]
    bad = pen_frames | sliding.any(axis=1)
    max_pen = max(float(-c.dist[on_floor].min()) if on_floor.any() else 0.0,
                  float(-corner_z.min()) if T else 0.0, 0.0)
    return {"ok": not bad.any(), "frames": frame_list(bad),
            "max_penetration_m": round(max_pen, 4),
            "skating_frames": frame_list(sliding), "penetrations": pen, "skating": skating,
            "low_swing_frames": frame_list(low_swing.any(axis=1)),
            "non_foot_contacts": non_foot}


def _contact_speed(corners: np.ndarray, labels: np.ndarray, fps: float) -> np.ndarray:
    """(T, 2, 4) horizontal corner speed (m/s) while labelled in contact: the central difference
    over the neighbouring frames that are in contact too (one-sided at a touchdown or lift-off
    frame, so the swing is not mixed in; 0 for a contact phase of one frame)."""
    d = np.diff(corners[..., :2], axis=0) * fps                         # (T-1, 2, 4, 2) velocity steps
    both = (labels[1:] & labels[:-1])[:, :, None, None]
    d = np.where(both, d, 0.0)
    n = both[..., 0].astype(float)                                      # (T-1, 2, 1)
    total = np.zeros(corners.shape[:3] + (2,))
    count = np.zeros(corners.shape[:3])
    total[1:] += d
    total[:-1] += d
    count[1:] += n
    count[:-1] += n
    return np.linalg.norm(total, axis=-1) / np.maximum(count, 1.0)

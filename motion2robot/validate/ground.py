"""The floor: geoms (and sole corners) below it, planted soles that slip or twist, swing feet
that skim it, as hardware would feel them.

- penetration: any robot geom deeper than ``ground_depth`` into the floor (from the contacts of
  the check model), or a sole corner lower than ``-ground_depth`` (a foot's geoms and its sole
  corners are reported together as "left foot" / "right foot");
- slipping: a point of a sole's edges (:mod:`~motion2robot.validate.sole`: corners and edge
  points) lower than ``touch_height`` in two consecutive frames is planted; if it moves
  horizontally faster than ``slip_speed`` between them, the sole slips. The fastest point
  decides, so a sole twisting about its pinned centre fails at its corners. Each slip is
  worded as a twist when the sole's rotation (yaw rate times the corners' distance from the
  centre) moves its points more than the centre moves, as a slide otherwise. Geometry decides,
  not the motion's contact labels: the floor does not read them;
- skimming: a foot with no planted point between two frames (a swing foot, lifting off or
  touching down included) whose edge points stay within ``swing_clearance`` of the floor in both
  frames while moving horizontally faster than ``slip_speed``: a foot that scuffs on hardware;
- non-foot contacts (figures only): bodies other than the feet touching the floor.

Runs of violating frames shorter than ``min_run`` are ignored. Units: metres, seconds.
"""

from __future__ import annotations

import numpy as np

from motion2robot.validate.context import Context
from motion2robot.validate.frames import frame_list, keep_runs
from motion2robot.validate.models import body_name, floor_geom
from motion2robot.validate.sole import SIDES, edge_motion, point_name, swing_clearance, yaw_rate


def ground(ctx: Context) -> dict:
    """Penetration, slipping and skimming verdict, with the non-foot contacts as figures."""
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

    feet_out, feet_bad = feet_on_floor(ctx)
    touching = on_floor & (c.dist < 1e-3) & ~np.isin(body, feet)
    non_foot = [{"body": body_name(m, b), "frames": sorted({int(f) for f in c.frame[touching & (body == b)]})}
                for b in np.unique(body[touching])]
    bad = pen_frames | feet_bad
    max_pen = max(float(-c.dist[on_floor].min()) if on_floor.any() else 0.0,
                  float(-corner_z.min()) if T else 0.0, 0.0)
    return {"ok": not bad.any(), "frames": frame_list(bad),
            "max_penetration_m": round(max_pen, 4),
            "penetrations": pen, **feet_out, "non_foot_contacts": non_foot}


def feet_on_floor(ctx: Context) -> tuple[dict, np.ndarray]:
    """Slipping planted soles and skimming swing feet (see the module docstring): their report
    entries and figures, and the (T,) bool mask of their frames."""
    opts, fps = ctx.options, ctx.kin.fps
    corners = ctx.kin.corners                                           # (T, 2, 4, 3)
    T = corners.shape[0]
    z, speed = edge_motion(corners, fps)                                # (T, 2, P), (T-1, 2, P)
    touch = z < opts.touch_height
    planted = touch[:-1] & touch[1:]
    clearance = swing_clearance(ctx.robot, opts)
    swing = ~planted.any(axis=2, keepdims=True)
    low = (z[:-1] < clearance) & (z[1:] < clearance)
    slip = planted & (speed > opts.slip_speed)
    skim = swing & low & (speed > opts.slip_speed)
    centre = np.linalg.norm(np.diff(corners[..., :2].mean(axis=2), axis=0), axis=-1) * fps      # (T-1, 2)
    reach = np.linalg.norm(corners[..., :2] - corners[..., :2].mean(axis=2, keepdims=True), axis=-1).max(axis=(0, 2))
    twist = yaw_rate(corners, fps) * reach > centre                     # (T-1, 2)
    slip_frames = keep_runs(_frames_of(slip.any(axis=2)), opts.min_run)   # (T, 2)
    skim_frames = keep_runs(_frames_of(skim.any(axis=2)), opts.min_run)
    slipping, skimming = [], []
    for k, side in enumerate(SIDES):
        for kind, sel in (("twist", twist[:, k]), ("slide", ~twist[:, k])):
            found = _worst(slip[:, k] & sel[:, None], speed[:, k], slip_frames[:, k])
            if found:
                i, p, mask = found
                slipping.append({"foot": side, "kind": kind, "speed_m_s": round(float(speed[i, k, p]), 4),
                                 "point": point_name(side, p), "worst_frame": i + 1,
                                 "frames": frame_list(_frames_of(mask.any(axis=1)))})
        found = _worst(skim[:, k], speed[:, k], skim_frames[:, k])
        if found:
            i, p, mask = found
            height = np.maximum(z[:-1, k], z[1:, k])[mask].min()
            skimming.append({"foot": side, "speed_m_s": round(float(speed[i, k, p]), 4),
                             "height_m": round(float(max(height, 0.0)), 4), "point": point_name(side, p),
                             "worst_frame": i + 1, "frames": frame_list(_frames_of(mask.any(axis=1)))})
    planted_speed = np.where(planted, speed, 0.0)
    return {"slipping": slipping, "slipping_frames": frame_list(slip_frames), "skimming": skimming,
            "skimming_frames": frame_list(skim_frames),
            "max_slip_m_s": round(float(planted_speed.max(initial=0.0)), 4),
            "slip_speed_m_s": opts.slip_speed, "swing_clearance_m": round(clearance, 4)}, \
        (slip_frames | skim_frames).any(axis=1)


def _frames_of(intervals: np.ndarray) -> np.ndarray:
    """(T-1, ...) masks of frame-to-frame intervals -> (T, ...) masks of the frames on both ends."""
    out = np.zeros((intervals.shape[0] + 1,) + intervals.shape[1:], dtype=bool)
    out[:-1] |= intervals
    out[1:] |= intervals
    return out


def _worst(mask: np.ndarray, speed: np.ndarray, kept: np.ndarray) -> tuple[int, int, np.ndarray] | None:
    """Of the (T-1, P) violating intervals and points ``mask`` whose frames survive in ``kept``
    (T,): the interval and point of the highest ``speed``, and the surviving mask."""
    mask = mask & kept[:-1, None] & kept[1:, None]
    if not mask.any():
        return None
    i, p = np.unravel_index(int(np.argmax(np.where(mask, speed, -1.0))), mask.shape)
    return int(i), int(p), mask

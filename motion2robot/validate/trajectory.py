"""Trajectory figures (never a verdict): how closely the robot's root ground path follows the
human's scaled root path (``meta["human_root_xy"]``, (T, 2) metres in the robot's world frame,
written by the retargeter).

Figures: mean / max / final position error (m); heading error (deg) between the directions of
travel over a +-``HEADING_WINDOW`` s window wherever the human moves at least
``MIN_TRAVEL`` m in it; path length ratio robot / human; and, when the physics playback ran, the
same position errors for the simulated root.
"""

from __future__ import annotations

import numpy as np

from motion2robot.validate.context import Context

#: Half window (s) over which the direction of travel is measured.
HEADING_WINDOW = 0.5
#: Human travel (m) within the window below which the heading is not compared.
MIN_TRAVEL = 0.05


def human_root_xy(ctx: Context) -> np.ndarray | None:
    raw = ctx.motion.meta.get("human_root_xy")
    if raw is None:
        return None
    try:
        xy = np.asarray(raw, dtype=np.float64)
    except (TypeError, ValueError):
        return None
    return xy if xy.shape == (ctx.kin.num_frames, 2) and np.isfinite(xy).all() else None


def _direction(xy: np.ndarray, w: int) -> tuple[np.ndarray, np.ndarray]:
    T = len(xy)
    a = np.clip(np.arange(T) - w, 0, T - 1)
    b = np.clip(np.arange(T) + w, 0, T - 1)
    d = xy[b] - xy[a]
    return np.arctan2(d[:, 1], d[:, 0]), np.linalg.norm(d, axis=1)


def control_error(ctx: Context) -> dict:
    """Robot root vs the requested trajectory (``meta["control_xy"]``, robot metres, None where a
    frame is not controlled): mean / max in robot metres and, divided by ``control_scale``, in
    human metres; {} when the motion carries no control path."""
    raw, scale = ctx.motion.meta.get("control_xy"), ctx.motion.meta.get("control_scale")
    if not raw or len(raw) != ctx.kin.num_frames or not scale:
        return {}
    on = np.array([p is not None for p in raw])
    if not on.any():
        return {}
    target = np.array([p for p in raw if p is not None], dtype=np.float64)
    err = np.linalg.norm(ctx.kin.qpos[on, :2] - target, axis=1)
    return {"control_frames": int(on.sum()), "control_source": ctx.motion.meta.get("control_source"),
            "control_mean_error_m": round(float(err.mean()), 4), "control_max_error_m": round(float(err.max()), 4),
            "control_mean_error_human_m": round(float(err.mean()) / float(scale), 4),
            "control_max_error_human_m": round(float(err.max()) / float(scale), 4)}


def trajectory(ctx: Context, sim_root_xy: np.ndarray | None = None) -> dict:
    """Root path figures against the human's scaled root path, and against the requested
    trajectory when the motion carries one (``ok`` is always True)."""
    human = human_root_xy(ctx)
    if human is None:
        return {"ok": True, "skipped": "no human root path in the meta",
                "frames": [], **control_error(ctx)}
    robot = ctx.kin.qpos[:, :2]
    err = np.linalg.norm(robot - human, axis=1)
    w = max(1, round(HEADING_WINDOW * ctx.fps))
    ah, dh = _direction(human, w)
    ar, _ = _direction(robot, w)
    moving = dh >= MIN_TRAVEL
    dhead = np.degrees(np.abs((ar - ah + np.pi) % (2 * np.pi) - np.pi))[moving]
    length = lambda p: float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
    lh = length(human)
    out = {
        "ok": True, "frames": [],
        "mean_error_m": round(float(err.mean()), 4), "max_error_m": round(float(err.max()), 4),
        "final_error_m": round(float(err[-1]), 4),
        "heading_error_mean_deg": round(float(dhead.mean()), 2) if dhead.size else None,
        "heading_error_max_deg": round(float(dhead.max()), 2) if dhead.size else None,
        "human_path_m": round(lh, 3), "path_length_ratio": round(length(robot) / lh, 3) if lh > 1e-6 else None,
        **control_error(ctx),
    }
    if sim_root_xy is not None:
        ok = ~np.isnan(sim_root_xy).any(axis=1)
        if ok.any():
            e = np.linalg.norm(sim_root_xy[ok] - human[ok], axis=1)
            out["playback_mean_error_m"] = round(float(e.mean()), 4)
            out["playback_max_error_m"] = round(float(e.max()), 4)
    return out

"""Balance: the CoM's and the ZMP's ground projections against the support polygon, per frame.

The support polygon is the convex hull of the sole corners that push on the floor (see
:func:`~motion2robot.validate.context.support_corners`); margins are signed distances to its
boundary in metres (positive inside). The ZMP is the multi-body one from the inverse dynamics
(:mod:`~motion2robot.validate.dynamics`), so it includes every link's acceleration, not only the
cart-table approximation. A frame without any supporting corner is flight.

Verdict: fails where the ZMP is outside the polygon by more than ``zmp_tolerance`` for at least
``min_run`` frames, on flight frames unless ``allow_flight``, and where the ZMP is inside but no
friction-feasible contact forces supply the required wrench (the feet would slip or spin: see
:mod:`~motion2robot.validate.contact_forces`). The CoM (static) margin is reported as a figure and
in the reasons.
"""

from __future__ import annotations

import numpy as np

from motion2robot.validate.context import Context
from motion2robot.validate.frames import first_time, frame_list, keep_runs
from motion2robot.validate.polygon import signed_distance


def margins(ctx: Context) -> tuple[np.ndarray, np.ndarray]:
    """(com_margin, zmp_margin), each (T,) metres; NaN in flight (and where the ZMP is undefined)."""
    T = ctx.kin.num_frames
    pts = ctx.kin.corners[..., :2].reshape(T, 8, 2)
    act = ctx.support.reshape(T, 8)
    both = signed_distance(pts, act, np.stack([ctx.kin.com[:, :2], ctx.dyn.zmp_xy], axis=1))
    return both[:, 0], both[:, 1]


def _worst(margin: np.ndarray, mask: np.ndarray) -> tuple[float, int] | None:
    if not mask.any():
        return None
    rows = np.flatnonzero(mask)
    k = rows[np.nanargmin(margin[rows])]
    return float(-margin[k]), int(k)


def _slip_worst(ctx: Context, slip: np.ndarray) -> dict | None:
    """The largest force and twist the floor could not supply in the ``slip`` frames."""
    if not slip.any():
        return None
    res = ctx.dyn.residual[slip]
    force = np.linalg.norm(res[:, :3], axis=1)
    k = int(np.flatnonzero(slip)[int(np.argmax(force + np.abs(res[:, 5])))])
    return {"force_n": round(float(force.max()), 3), "twist_nm": round(float(np.abs(res[:, 5]).max()), 4),
            "frame": k, "mu": [round(float(v), 3) for v in ctx.dyn.mu]}


def balance(ctx: Context, com_zmp: tuple[np.ndarray, np.ndarray] | None = None) -> dict:
    """CoM and ZMP margins, flight frames, and the ZMP verdict (``com_zmp``: :func:`margins`, if
    already computed)."""
    opts, fps = ctx.options, ctx.fps
    com_m, zmp_m = margins(ctx) if com_zmp is None else com_zmp
    flight = ~ctx.support.any(axis=(1, 2))
    zmp_out = keep_runs(np.nan_to_num(zmp_m, nan=np.inf) < -opts.zmp_tolerance, opts.min_run)
    com_out = np.nan_to_num(com_m, nan=np.inf) < 0
    zmp_in = np.nan_to_num(zmp_m, nan=-np.inf) >= -opts.zmp_tolerance
    slip = keep_runs(~flight & zmp_in & ~ctx.dyn.supplied, opts.min_run)
    bad = zmp_out | slip | (flight if not opts.allow_flight else np.zeros_like(flight))
    out: dict = {"ok": not bad.any(), "frames": frame_list(bad)}
    out["slip_frames"] = frame_list(slip)
    out["slip_worst"] = _slip_worst(ctx, slip)
    out["min_com_margin_m"] = round(float(np.nanmin(com_m)), 4) if np.isfinite(com_m).any() else None
    out["min_zmp_margin_m"] = round(float(np.nanmin(zmp_m)), 4) if np.isfinite(zmp_m).any() else None
    out["flight_frames"] = frame_list(flight)
    out["zmp_outside_frames"] = frame_list(zmp_out)
    out["com_outside_frames"] = frame_list(com_out)
    w = _worst(zmp_m, zmp_out)
    out["zmp_worst"] = None if w is None else {"by_m": round(w[0], 4), "frame": w[1], "time_s": round(w[1] / fps, 3)}
    w = _worst(com_m, com_out)
    out["com_worst"] = None if w is None else {"by_m": round(w[0], 4), "frame": w[1], "time_s": round(w[1] / fps, 3)}
    out["com_first_out_s"] = first_time(out["com_outside_frames"], fps)
    out["zmp_first_out_s"] = first_time(out["zmp_outside_frames"], fps)
    out["flight_first_s"] = first_time(out["flight_frames"], fps)
    return out

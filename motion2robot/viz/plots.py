"""Matplotlib (Agg, no display) figures of a feasibility report's per-frame evidence.

Each ``plot_*`` takes plain arrays (time in frames at ``fps``, SI units) and returns a
``matplotlib.figure.Figure`` (no pyplot global state); :func:`figure_png` turns it into PNG bytes.
"""

from __future__ import annotations

import io
from typing import Sequence

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

LIMIT_STYLE = dict(color="#c0392b", linestyle="--", linewidth=1.0)
LEFT_RIGHT = ("left", "right")


def figure_png(fig: Figure, dpi: int = 90) -> bytes:
    """PNG bytes of a figure."""
    FigureCanvasAgg(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def _new(nrows: int = 1, height: float = 3.2, width: float = 9.0) -> tuple[Figure, list]:
    fig = Figure(figsize=(width, height * nrows), layout="constrained")
    axes = fig.subplots(nrows, 1, squeeze=False)[:, 0]
    return fig, list(axes)


def _shade(ax, t: np.ndarray, mask: np.ndarray, color: str, label: str | None = None) -> None:
    """Shade the time spans where ``mask`` is true."""
    if mask.any():
        ax.fill_between(t, 0, 1, where=mask, transform=ax.get_xaxis_transform(), color=color,
                        alpha=0.25, step="mid", linewidth=0, label=label)


def _failing_mask(n: int, frames: Sequence[int]) -> np.ndarray:
    mask = np.zeros(n, dtype=bool)
    idx = np.asarray([f for f in frames if 0 <= f < n], dtype=int)
    mask[idx] = True
    return mask


def _per_joint(ax, t: np.ndarray, values: np.ndarray, names: Sequence[str], badness: np.ndarray,
               top: int = 5, failing: Sequence[int] = ()) -> None:
    """All joints as thin grey lines; the ``top`` worst (highest ``badness``) in colour and named;
    the ``failing`` frames shaded red."""
    _shade(ax, t, _failing_mask(len(t), failing), "#c0392b", "failing frames")
    order = np.argsort(badness)[::-1]
    worst = set(order[:top].tolist())
    for j in range(values.shape[1]):
        if j not in worst:
            ax.plot(t, values[:, j], color="0.75", linewidth=0.7)
    for j in order[:top]:
        ax.plot(t, values[:, j], linewidth=1.5, label=names[j])
    ax.legend(loc="upper right", fontsize=7, ncol=min(top, 3), framealpha=0.8)
    ax.set_xlabel("time (s)")
    ax.grid(alpha=0.3)


def plot_joint_angles(q: np.ndarray, lower: np.ndarray, upper: np.ndarray, names: Sequence[str],
                      fps: float, failing: Sequence[int] = ()) -> Figure:
    """Joint angles as a fraction of their range: 0 = lower limit, 1 = upper limit (rad -> unitless)."""
    span = np.where(upper - lower > 1e-9, upper - lower, 1.0)
    u = (q - lower) / span
    t = np.arange(len(q)) / fps
    fig, (ax,) = _new()
    _per_joint(ax, t, u, names, np.max(np.abs(u - 0.5), axis=0), failing=failing)
    for y in (0.0, 1.0):
        ax.axhline(y, **LIMIT_STYLE)
    ax.set_ylabel("position in range\n(0 = lower, 1 = upper)")
    ax.set_title("Joint angles against limits")
    return fig


def plot_ratio(ratio: np.ndarray, names: Sequence[str], fps: float, title: str, ylabel: str,
               failing: Sequence[int] = ()) -> Figure:
    """A per-joint ratio to its limit (joint speed / velocity limit, torque / torque limit)."""
    t = np.arange(len(ratio)) / fps
    fig, (ax,) = _new()
    _per_joint(ax, t, ratio, names, np.max(ratio, axis=0), failing=failing)
    ax.axhline(1.0, **LIMIT_STYLE)
    ax.set_ylim(bottom=0)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    return fig


def convex_hull(points: np.ndarray) -> np.ndarray:
    """(k, 2) corners of the convex hull of (m, 2) points, counter-clockwise, closed (Andrew's
    monotone chain)."""
    pts = sorted(map(tuple, np.asarray(points, dtype=float)))
    if len(pts) < 3:
        return np.array(pts + pts[:1])

    def half(seq):
        out: list = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    hull = lower[:-1] + upper[:-1]
    return np.array(hull + hull[:1])


def convex_outline(points: np.ndarray) -> np.ndarray:
    """(k, 2) points ordered around their centroid (closed: first point repeated at the end)."""
    c = points.mean(axis=0)
    order = np.argsort(np.arctan2(points[:, 1] - c[1], points[:, 0] - c[0]))
    p = points[order]
    return np.vstack([p, p[:1]])


def plot_balance(com_xy: np.ndarray, zmp_xy: np.ndarray | None, soles_xy: np.ndarray | None,
                 contacts: np.ndarray | None, margin: np.ndarray | None, fps: float,
                 failing: Sequence[int] = (), zmp_margin: np.ndarray | None = None) -> Figure:
    """Top view (x forward, y left, metres) of the CoM and ZMP paths over the soles in contact,
    and the support margins (m, negative = outside the support polygon) over time.

    soles_xy: (T, 2, 4, 2) sole corner positions [left, right] or None. The view is framed on the
    soles and the CoM: ZMP excursions far outside are cut at the edge (their count is noted)."""
    fig = Figure(figsize=(9.0, 7.0), layout="constrained")
    ax, ax2 = fig.subplots(2, 1, height_ratios=[2.2, 1])
    T = len(com_xy)
    frame_pts = [com_xy]
    if soles_xy is not None:
        frame_pts.append(soles_xy.reshape(-1, 2))
        step = max(1, T // 60)
        for f in range(0, T, step):
            for side in range(2):
                if contacts is None or contacts[f, side]:
                    o = convex_outline(soles_xy[f, side])
                    ax.plot(o[:, 0], o[:, 1], color=("#27ae60", "#2980b9")[side], alpha=0.35, linewidth=0.8)
        for f in range(0, T, max(1, T // 8)):  # the support polygon itself at a few frames
            on = [side for side in range(2) if contacts is None or contacts[f, side]]
            if on:
                h = convex_hull(soles_xy[f, on].reshape(-1, 2))
                ax.plot(h[:, 0], h[:, 1], color="0.3", linestyle=":", linewidth=0.9)
        ax.plot([], [], color="#27ae60", label="left sole (in contact)")
        ax.plot([], [], color="#2980b9", label="right sole (in contact)")
        ax.plot([], [], color="0.3", linestyle=":", label="support polygon (some frames)")
    pts = np.vstack(frame_pts)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = 0.25 * max(float(np.max(hi - lo)), 0.05)
    lo, hi = lo - pad, hi + pad
    ax.plot(com_xy[:, 0], com_xy[:, 1], color="black", linewidth=1.6, label="CoM (ground projection)")
    if zmp_xy is not None:
        out = int(np.sum(np.any((zmp_xy < lo) | (zmp_xy > hi), axis=1)))
        ax.plot(zmp_xy[:, 0], zmp_xy[:, 1], color="#e67e22", linewidth=0.6, alpha=0.7, marker=".", markersize=3,
                label="ZMP" + (f" ({out} frames beyond this view)" if out else ""))
    bad = np.array([f for f in failing if 0 <= f < T], dtype=int)
    track = zmp_xy if zmp_xy is not None else com_xy
    if bad.size:
        ax.scatter(track[bad, 0], track[bad, 1], color="#c0392b", s=10, zorder=3, label="failing frames")
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x (m, forward)")
    ax.set_ylabel("y (m, left)")
    ax.set_title("CoM and ZMP against the support polygon (from above)")
    ax.legend(loc="best", fontsize=7)
    ax.grid(alpha=0.3)
    t = np.arange(T) / fps
    shown = []
    for values, label, color in ((margin, "CoM margin", "#8e44ad"), (zmp_margin, "ZMP margin", "#e67e22")):
        if values is not None:
            cm = np.asarray(values, dtype=float) * 100.0
            ax2.plot(t, cm, color=color, linewidth=1.2, label=label)
            shown.append(cm)
    if shown:
        allv = np.concatenate(shown)
        ax2.axhline(0.0, **LIMIT_STYLE)
        _shade(ax2, t, shown[0] < 0, "#c0392b", "CoM outside")
        ax2.set_ylim(max(float(np.nanmin(allv)), -10.0) - 0.5, float(np.nanmax(allv)) + 0.5)
        ax2.legend(loc="lower right", fontsize=7)
    ax2.set_xlabel("time (s)")
    ax2.set_ylabel("support margin (cm)\n(cut at -10)")
    ax2.grid(alpha=0.3)
    return fig


def plot_feet(foot_height: np.ndarray, contacts: np.ndarray | None, fps: float) -> Figure:
    """Lowest sole corner height (cm) per foot with the contact phases shaded."""
    t = np.arange(len(foot_height)) / fps
    fig, axes = _new(2, height=2.0)
    for side, ax in enumerate(axes):
        ax.plot(t, foot_height[:, side] * 100.0, color=("#27ae60", "#2980b9")[side], linewidth=1.3)
        if contacts is not None:
            _shade(ax, t, np.asarray(contacts[:, side], dtype=bool), "0.5", "contact")
            ax.legend(loc="upper right", fontsize=7)
        ax.axhline(0.0, **LIMIT_STYLE)
        h = foot_height[:, side] * 100.0
        ax.set_ylim(min(float(np.nanmin(h)), 0.0) - 0.5, max(float(np.nanmax(h)), 2.0) + 0.5)
        ax.set_ylabel(f"{LEFT_RIGHT[side]} foot\nheight (cm)")
        ax.grid(alpha=0.3)
    axes[0].set_title("Foot heights and contact phases")
    axes[-1].set_xlabel("time (s)")
    return fig

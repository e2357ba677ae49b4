"""A picture of a clip: the skeleton at a few frames (side view) and the root path from above.

matplotlib is imported inside :func:`plot_motion` with the headless Agg backend.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2robot.motion.human import KP, SMPL22, SMPL22_PARENTS, HumanMotion


def plot_motion(m: HumanMotion, out: str | Path, frames: int = 5, title: str | None = None) -> Path:
    """Write a PNG: left, side view (x forward, z up) of the skeleton at ``frames`` evenly spaced
    frames, spread along x for readability; right, the pelvis path seen from above (x, y) with the
    start marked and the facing direction at a few frames."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    out = Path(out)
    pos = m.positions
    idx = np.unique(np.linspace(0, m.num_frames - 1, frames).round().astype(int))
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 5), gridspec_kw={"width_ratios": [3, 2]})
    cmap = plt.get_cmap("viridis")
    spread = 0.8
    for n, f in enumerate(idx):
        p = pos[f].copy()
        p[:, 0] += n * spread - p[KP["pelvis"], 0]
        color = cmap(n / max(len(idx) - 1, 1))
        for j, parent in enumerate(SMPL22_PARENTS):
            if parent >= 0:
                lw = 2.5 if SMPL22[j].startswith("left") else 1.2
                ax1.plot([p[parent, 0], p[j, 0]], [p[parent, 2], p[j, 2]], color=color, lw=lw)
        ax1.scatter(p[:, 0], p[:, 2], s=6, color=color)
        ax1.text(n * spread, -0.12, f"{f / m.fps:.2f} s", ha="center", fontsize=8)
    ax1.axhline(0.0, color="grey", lw=0.8)
    ax1.set_aspect("equal")
    ax1.set_ylim(-0.2, max(2.0, float(pos[..., 2].max()) + 0.1))
    ax1.set_xlabel("frames spread along x (m); thick = left side")
    ax1.set_ylabel("z (m)")
    ax1.set_title("skeleton, side view (facing +x at frame 0)")
    root = pos[:, KP["pelvis"], :2]
    ax2.plot(root[:, 0], root[:, 1], color="black", lw=1.2)
    ax2.scatter(root[:1, 0], root[:1, 1], color="green", s=40, label="start", zorder=3)
    ax2.scatter(root[-1:, 0], root[-1:, 1], color="red", s=40, label="end", zorder=3)
    for f in idx:
        left = pos[f, KP["left_hip"], :2] - pos[f, KP["right_hip"], :2]
        fwd = np.array([left[1], -left[0]])
        fwd = 0.25 * fwd / max(np.linalg.norm(fwd), 1e-9)
        ax2.annotate("", xy=root[f] + fwd, xytext=root[f], arrowprops={"arrowstyle": "->", "color": "C0"})
    span = max(float(np.ptp(root, axis=0).max()), 0.5)
    c = root.mean(axis=0)
    ax2.set_xlim(c[0] - span, c[0] + span)
    ax2.set_ylim(c[1] - span, c[1] + span)
    ax2.set_aspect("equal")
    ax2.set_xlabel("x (m)")
    ax2.set_ylabel("y (m, subject's left at frame 0)")
    ax2.set_title("pelvis path from above (arrows: facing)")
    ax2.legend(loc="best", fontsize=8)
    fig.suptitle(title or str(m.meta.get("source", "")), fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=90, bbox_inches="tight")
    plt.close(fig)
    return out


"""The edit's own robot solution, retargeted only over the frames it changed (plus a pad).

The composition takes the edit's solution only at changed frames and in the blend around them; a
solve of the edited human motion trimmed to those frames plus ``pad`` seconds on each side gives
the same frames at a fraction of a whole-clip solve (the trimmed solve's edge effects fall in the
pad, where the composition keeps the source exactly). Frames map by time: robot frame r of a motion
at ``fps_r`` played ``tempo`` times slower shows human time r / (fps_r * tempo) seconds.
"""

from __future__ import annotations

import math

import numpy as np

from motion2robot.motion.human import HumanMotion
from motion2robot.motion.ops import trim
from motion2robot.robot_motion import RobotMotion

#: Above this share of the clip, the whole edit is retargeted (a window would save little).
WHOLE_SHARE = 0.6


def human_frames(robot_frames: np.ndarray, robot_fps: float, tempo: float, human_fps: float) -> np.ndarray:
    """Robot frame indices -> (fractional) human frame indices."""
    return np.asarray(robot_frames, dtype=float) * human_fps / (robot_fps * tempo)


def _interp(q: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Rows of ``q`` at fractional indices ``u`` (linear; the root quaternion renormalised)."""
    u = np.clip(u, 0, len(q) - 1)
    a = np.floor(u).astype(int)
    b = np.minimum(a + 1, len(q) - 1)
    w = (u - a)[:, None]
    qa, qb = q[a], q[b]
    flip = np.sum(qa[:, 3:7] * qb[:, 3:7], axis=1) < 0
    qb = qb.copy()
    qb[flip, 3:7] *= -1.0
    out = (1.0 - w) * qa + w * qb
    out[:, 3:7] /= np.linalg.norm(out[:, 3:7], axis=1, keepdims=True)
    return out


def edit_solution(edit: HumanMotion, robot, options, src: RobotMotion, changed: np.ndarray,
                  pad_seconds: float) -> tuple[np.ndarray, tuple[int, int]]:
    """(qpos on the source's robot frames: the edit's solution in the window, the source's
    outside; the window [lo, hi) in robot frames). ``changed``: (T,) human frames where any part
    changed; ``options``: the source's scale, tempo and legs fixed."""
    from motion2robot.retarget import retarget

    t_h, t_r = edit.num_frames, src.num_frames
    tempo = float(src.meta.get("tempo", 1.0) or 1.0)
    idx = np.flatnonzero(changed)
    pad = int(math.ceil(pad_seconds * edit.fps))
    a, b = max(0, int(idx[0]) - pad), min(t_h - 1, int(idx[-1]) + pad)
    if b - a + 1 > WHOLE_SHARE * t_h:
        a, b = 0, t_h - 1
    qw = retarget(edit if (a, b) == (0, t_h - 1) else trim(edit, a, b + 1), robot, options).qpos
    per = src.fps * tempo / edit.fps  # robot frames per human frame
    lo = 0 if a == 0 else int(math.ceil(a * per - 1e-9))
    hi = t_r if b == t_h - 1 else min(t_r, int(math.floor(b * per + 1e-9)) + 1)
    q = src.qpos.copy()
    q[lo:hi] = _interp(qw, np.arange(lo, hi) - a * per)
    return q, (lo, hi)

"""Keep the two feet's pinned sole placements apart in double support.

Each contact phase is anchored where its first frame put the sole
(:func:`~motion2robot.retarget.contacts.anchor_soles`), so in double support the two anchors may
come from different frames and overlap: the pinned feet (and then the shins) collide whatever the
joints do. Phases are visited in order of their first frame; a phase that begins while the other
foot is already pinned has its anchor moved the shortest way (in the floor plane) that gives the
feet's self-collision capsules (flat on the floor, so a 2D segment distance) their clearance.
"""

from __future__ import annotations

import numpy as np

from motion2robot.retarget import native
from motion2robot.retarget.contacts import phases

#: Directions (evenly spread) and lengths (m) tried for the push of an anchor.
DIRECTIONS = 32
STEPS = np.linspace(0.0, 0.15, 301)
#: Lengths tried per vectorised batch (the search stops at the first batch with a clear move).
CHUNK = 25
_ANGLES = np.linspace(0.0, 2 * np.pi, DIRECTIONS, endpoint=False)
_MOVES = STEPS[:, None, None] * np.stack([np.cos(_ANGLES), np.sin(_ANGLES)], -1)[None]   # (S, D, 2)


def segment_distance(p: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances (...) between segments pq and ab (arrays (..., 2) or (..., 3), broadcast; Ericson,
    Real-Time Collision Detection 5.1.9)."""
    d1, d2, r = q - p, b - a, p - a
    aa, ee, ff = (d1 * d1).sum(-1) + 1e-12, (d2 * d2).sum(-1) + 1e-12, (d2 * r).sum(-1)
    c, bb = (d1 * r).sum(-1), (d1 * d2).sum(-1)
    s = np.clip((bb * ff - c * ee) / np.maximum(aa * ee - bb * bb, 1e-12), 0.0, 1.0)
    t = (bb * s + ff) / ee
    s = np.where(t < 0, np.clip(-c / aa, 0, 1), np.where(t > 1, np.clip((bb - c) / aa, 0, 1), s))
    t = np.clip(t, 0.0, 1.0)
    return np.linalg.norm(p + s[..., None] * d1 - a - t[..., None] * d2, axis=-1)


def _push(seg: np.ndarray, other: np.ndarray, need: float) -> np.ndarray:
    """Shortest move (2,) of segment ``seg`` (2, 2) (over a grid of directions and lengths) after
    which it is at least ``need`` from ``other`` (2, 2); the zero move when it already is (the
    C kernel of :mod:`~.native`, else numpy: the same numbers)."""
    fast = native.push(seg, other, need, _MOVES)
    if fast is not None:
        return fast
    if segment_distance(seg[0], seg[1], other[0], other[1]) >= need:
        return np.zeros(2)
    for lo in range(0, len(STEPS), CHUNK):  # lengths in increasing chunks: pushes are mostly short
        moves = _MOVES[lo:lo + CHUNK]                                                 # (S, D, 2)
        gap = segment_distance(seg[0] + moves, seg[1] + moves, other[0], other[1])    # (S, D)
        ok = (gap >= need).any(axis=1)
        if ok.any():
            first = int(np.argmax(ok))
            return moves[first, int(np.argmax(gap[first]))]
    return moves[-1, int(np.argmax(gap[-1]))]


def foot_segments(corners: np.ndarray, local: np.ndarray) -> np.ndarray:
    """World (..., 2, 2) ends of foot capsules whose soles sit at ``corners`` (..., 4, 3); ``local``
    (2, 2) the capsule ends relative to the sole centre in the sole's frame (x forward). NaN soles
    give NaN ends."""
    xy = corners[..., :2]
    centre = xy.mean(axis=-2)                                           # (..., 2)
    fwd = (xy[..., 0, :] + xy[..., 1, :]) - (xy[..., 2, :] + xy[..., 3, :])
    fwd = fwd / np.maximum(np.linalg.norm(fwd, axis=-1, keepdims=True), 1e-12)
    c, s = fwd[..., None, 0], fwd[..., None, 1]                         # (..., 1)
    x = centre[..., None, 0] + c * local[:, 0] - s * local[:, 1]
    y = centre[..., None, 1] + s * local[:, 0] + c * local[:, 1]
    return np.stack([x, y], axis=-1)


def separate_anchors(anchors: np.ndarray, labels: np.ndarray, local: np.ndarray, radius: np.ndarray,
                     clearance: float) -> tuple[np.ndarray, float]:
    """``anchors`` (T, 2, 4, 3) pinned sole corners (NaN outside contact) with each phase that
    begins in the other foot's phase moved the shortest way (rigidly, in x/y) so that the feet's capsules (``local`` (2 feet, 2 ends, 2) sole-frame
    ends, ``radius`` (2,) m) are at least ``clearance`` (m) apart from the other foot's anchor
    over their common frames. Returns the anchors and the largest push (m)."""
    out = anchors.copy()
    ph = sorted(phases(labels), key=lambda x: (x[1], x[0]))
    pushed = 0.0
    need = float(radius[0] + radius[1] + clearance)
    for k, (f, a, b) in enumerate(ph):
        g = 1 - f
        older = [(a2, b2) for (f2, a2, b2) in ph[:k] if f2 == g and a2 <= a < b2]
        if not older:
            continue
        other = foot_segments(out[a, g], local[g])
        move = _push(foot_segments(out[a, f], local[f]), other, need)
        out[a:b, f, :, :2] += move
        total = move
        pushed = max(pushed, float(np.linalg.norm(total)))
    return out, pushed


_FEET: dict = {}


def foot_capsules(robot) -> tuple[np.ndarray, np.ndarray] | None:
    """(2, 2, 2) sole-frame xy ends and (2,) radii (m) of the feet's self-collision capsules
    (:mod:`~motion2robot.retarget.collision`), or None when the retargeter keeps no foot-foot pair
    (cached per robot model)."""
    key = (robot.name, robot.model_hash)
    if key not in _FEET:
        _FEET[key] = _foot_capsules(robot)
    return _FEET[key]


def _foot_capsules(robot) -> tuple[np.ndarray, np.ndarray] | None:
    from motion2robot.retarget.collision import collision_pairs

    feet = [int(b) for b in robot.foot_bodies]
    caps = {}
    for p in collision_pairs(robot):
        if {p.a.body, p.b.body} == set(feet) and hasattr(p.b, "radius"):  # capsule-capsule
            caps = {p.a.body: p.a, p.b.body: p.b}
    if not caps:
        return None
    local = np.array([[(end - np.asarray(cfg.sole_center))[:2] for end in (caps[b].p0, caps[b].p1)]
                      for b, cfg in zip(feet, robot.config.feet)])
    return local, np.array([caps[b].radius for b in feet])

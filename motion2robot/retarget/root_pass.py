"""Exact final pass that moves only the floating root (a rotation about the vertical, then a
translation) so that no sole corner is below the floor and the stance sole neither slides nor spins,
without touching the joint angles (so the joint and velocity limits, already exact, stay exact).

A rigid motion of the root moves every body rigidly: the sole corners of frame ``t`` after the pass
are ``R(yaw[t]) (x - pivot[t]) + pivot[t] + shift[t]`` of the corners before it, so the pass is
closed-form and vectorised. A rotation about the vertical changes no height, no joint angle, no
self-collision gap and no CoM-vs-sole relation.

- Yaw: per frame, the stance foot (the only continuing contact) keeps the yaw it had in the
  previous frame, so it keeps its yaw of the moment it became the only one in contact. In double
  support the two feet share the rotation that best fits their eight corners when that keeps both
  within twice the slide tolerance; when the joints turn the feet apart faster, the rotation is
  kept (holding the older foot's yaw there would swing the other foot about it: measured worse on
  the standing clips than leaving the joints' relative turn as it is). Frames without a continuing
  contact let the correction relax towards zero (time constant YAW_RELAX_S). The correction's mean
  is removed (no net heading offset; a constant turn keeps the stance yaw exact). With a
  ``yaw_slide`` budget (m/s of the held sole's corners, default 0 = exact) the offset also follows
  the correction's moving average over YAW_TREND_S at the rate that budget allows (long drift).
  The pivot is the mid-point of the two soles (any vertical axis works: the translation below pins
  the stance sole).
- Horizontal (xy): per frame, the feet in contact in this frame and the previous one are
  "continuing"; the root is moved by the opposite of the continuing stance sole's horizontal
  displacement, so that sole keeps its place (its anchor: where it was when it became the stance
  foot). In double support the two feet ask for shifts that differ by their relative motion: when
  that is within the slide tolerance both are served by the mean shift, else the foot that has been
  in contact longer is pinned. Frames without a continuing contact carry the shift (continuity).
- Vertical (z): contact frames put the lowest sole corner on the floor; frames without contact
  interpolate the contact frames' shift and are only raised where a corner would be below the floor.
- Smoothing (optional, for balance-on motions whose root acceleration moves the ZMP): the shift, not
  the path, is smoothed towards an acceleration target, and that smoothed shift is kept only in the
  frames where it keeps the floor and the stance sole within tolerance.

The centre of mass moves with the root and the feet, so its place in the support polygon of the
actual soles is unchanged by the rotation and the translation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2robot.retarget.smoothing import smooth_to_targets

#: Horizontal sole speed (m/s) the pass allows a foot in continuing contact (just under the 1 cm/s
#: of the acceptance figure): double support takes the mean shift when it keeps both feet under it.
SLIDE_TOLERANCE = 0.0095
#: Depth (m) a smoothed shift may leave below the floor before the frame falls back to the exact one.
FLOOR_TOLERANCE = 1e-4
#: Time constant (s) of the yaw correction's relaxation to zero in frames without a continuing contact.
YAW_RELAX_S = 0.25
#: Window (s) of the moving average of the yaw correction that its offset follows (heading drift).
YAW_TREND_S = 2.0
#: Default horizontal speed (m/s) of the held sole's corners that the yaw offset's drift correction
#: may cause while in contact: 0 = the held foot's yaw exact (then only the mean is removed).
YAW_SLIDE = 0.0


@dataclass(frozen=True)
class RootShift:
    """The root motion of the pass: per frame a rotation by ``yaw`` (T,) radians about the vertical
    through ``pivot`` (T, 2) (m, world xy), then ``shift`` (T, 3) metres; ``pinned`` (T,) the foot
    (0 left, 1 right, 2 both: mean shift, -1 none) that fixed the horizontal shift of each frame."""

    shift: np.ndarray
    pinned: np.ndarray
    yaw: np.ndarray | None = None
    pivot: np.ndarray | None = None

    def _yaw(self) -> tuple[np.ndarray, np.ndarray]:
        T = len(self.shift)
        return (np.zeros(T) if self.yaw is None else self.yaw,
                np.zeros((T, 2)) if self.pivot is None else self.pivot)

    def points(self, x: np.ndarray) -> np.ndarray:
        """World points ``x`` (T, ..., 3) moved with the root (metres)."""
        yaw, pivot = self._yaw()
        extra = (slice(None),) + (None,) * (x.ndim - 2)
        out = x.copy()
        out[..., :2] = _rotate(x[..., :2] - pivot[extra], yaw[extra]) + pivot[extra]
        return out + self.shift[extra]

    def apply(self, qpos: np.ndarray) -> np.ndarray:
        """``qpos`` (T, 7+n) (root xyz, quat wxyz, hinges) with the root moved; hinges untouched."""
        yaw, _ = self._yaw()
        out = qpos.copy()
        out[:, :3] = self.points(qpos[:, None, :3])[:, 0]
        h = 0.5 * yaw
        qz = np.column_stack([np.cos(h), np.zeros_like(h), np.zeros_like(h), np.sin(h)])
        out[:, 3:7] = _quat_mul(qz, qpos[:, 3:7])
        return out

    def figures(self) -> dict:
        norm = np.linalg.norm(self.shift, axis=1)
        yaw = np.abs(self._yaw()[0])
        return {"max_root_shift_m": float(norm.max()) if len(norm) else 0.0,
                "max_root_shift_z_m": float(np.abs(self.shift[:, 2]).max()) if len(norm) else 0.0,
                "max_root_yaw_rad": float(yaw.max()) if len(yaw) else 0.0,
                "root_shift_per_frame": norm.tolist(), "root_yaw_per_frame": yaw.tolist()}


def _rotate(xy: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """xy (..., 2) rotated by ``yaw`` (radians, broadcast against xy[..., 0]) about the origin."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack([c * xy[..., 0] - s * xy[..., 1], s * xy[..., 0] + c * xy[..., 1]], axis=-1)


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of (T, 4) wxyz quaternions."""
    w1, x1, y1, z1 = a.T
    w2, x2, y2, z2 = b.T
    return np.column_stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def foot_yaw(corners: np.ndarray) -> np.ndarray:
    """(T, 2) unwrapped yaw (radians) of each sole, from its corners (T, 2, 4, 3): the best-fit
    rotation about the vertical of the corners' xy about their centre, relative to frame 0."""
    xy = corners[..., :2] - corners[..., :2].mean(axis=2, keepdims=True)       # (T, 2, 4, 2)
    ref = xy[:1]
    cross = (ref[..., 0] * xy[..., 1] - ref[..., 1] * xy[..., 0]).sum(axis=-1)
    dot = (ref * xy).sum(axis=(-1)).sum(axis=-1)
    return np.unwrap(np.arctan2(cross, dot), axis=0)


def _turn(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(...,) best-fit rotation (radians, about the vertical) taking the xy points ``b`` (..., N, 2)
    onto ``a`` (..., N, 2), both about their centroids."""
    a = a - a.mean(axis=-2, keepdims=True)
    b = b - b.mean(axis=-2, keepdims=True)
    return np.arctan2((b[..., 0] * a[..., 1] - b[..., 1] * a[..., 0]).sum(axis=-1), (a * b).sum(axis=(-2, -1)))


def held_yaw(corners: np.ndarray, labels: np.ndarray, fps: float, tolerance: float) -> np.ndarray:
    """(T,) rotation (radians) about the vertical that keeps the stance foot's yaw (from the sole
    corners (T, 2, 4, 3)) in every frame where it is the only continuing contact (exactly); in
    double support both feet share the rotation that best fits their eight corners when it keeps
    every corner within 2 ``tolerance`` (m per frame) of its fitted place, else the rotation is kept
    (the feet turn relative to each other: the joints decide, as before the pass). Relaxes to zero
    with time constant YAW_RELAX_S in frames without a continuing contact."""
    T = len(labels)
    psi = np.zeros(T)
    if T < 2:
        return psi
    yaw = foot_yaw(corners)
    cont = labels[1:] & labels[:-1]
    both = cont.all(axis=1)
    held = np.where(both, 0, np.where(cont[:, 0], 0, np.where(cont[:, 1], 1, -1)))   # both: shared need
    need = yaw[:-1] - yaw[1:]                                          # (T-1, 2)
    if both.any():
        xy = corners[..., :2].reshape(T, 8, 2)
        a, b = xy[:-1][both], xy[1:][both]
        turn = _turn(a, b)
        fit = _rotate(b - b.mean(axis=1, keepdims=True), turn[:, None]) + a.mean(axis=1, keepdims=True)
        share = np.linalg.norm(fit - a, axis=-1).max(axis=1) <= 2 * tolerance
        rows = np.flatnonzero(both)
        need[rows[share]] = turn[share, None]
        need[rows[~share]] = 0.0                                       # the feet turn apart: keep the yaw
    keep = np.exp(-1.0 / (YAW_RELAX_S * fps))
    for t in range(1, T):
        f = held[t - 1]
        psi[t] = psi[t - 1] + need[t - 1, f] if f >= 0 else keep * psi[t - 1]
    return psi


def yaw_correction(corners: np.ndarray, labels: np.ndarray, fps: float, rate: float = 0.0,
                   window_s: float = YAW_TREND_S) -> np.ndarray:
    """(T,) root yaw correction (radians): :func:`held_yaw` less an offset that follows its moving
    average over ``window_s`` seconds at no more than ``rate`` (rad/s), so the heading does not
    drift away from the solver's (the human's) path. A constant offset (``rate`` 0: the mean) keeps
    the held foot's yaw exact; a varying one turns it by at most ``rate``."""
    psi = held_yaw(corners, labels, fps, SLIDE_TOLERANCE / fps)
    T = len(psi)
    if T == 0:
        return psi
    half = max(int(round(0.5 * window_s * fps)), 0)
    c = np.concatenate([[0.0], np.cumsum(psi)])
    lo, hi = np.maximum(np.arange(T) - half, 0), np.minimum(np.arange(T) + half + 1, T)
    trend = (c[hi] - c[lo]) / (hi - lo)                                # centred moving average
    offset = np.empty(T)
    offset[0] = trend[0] if rate > 0 else psi.mean()
    step = rate / fps
    for t in range(1, T):
        offset[t] = offset[t - 1] + np.clip(trend[t] - offset[t - 1], -step, step)
    return psi - offset


def _phase_start(labels: np.ndarray) -> np.ndarray:
    """(T, 2) first frame of the contact run each frame belongs to (-1 outside contact)."""
    T = len(labels)
    idx = np.arange(T)[:, None]
    prev = np.vstack([np.zeros((1, labels.shape[1]), dtype=bool), labels[:-1]])
    starts = np.where(labels & ~prev, idx, -1)
    return np.where(labels, np.maximum.accumulate(starts, axis=0), -1)


def horizontal_shift(centres: np.ndarray, labels: np.ndarray, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """(T, 2) root shift and (T,) pinned foot from the sole centres ``centres`` (T, 2, 2) (xy of each
    foot before the pass), contact labels (T, 2) and the per-frame slide ``tolerance`` (m); see the
    module docstring."""
    T = len(labels)
    if T < 2:
        return np.zeros((T, 2)), np.full(T, -1)
    cont = labels[1:] & labels[:-1]                                  # (T-1, 2) continuing contact
    need = centres[:-1] - centres[1:]                                # (T-1, 2 feet, 2) shift keeping each foot
    start = _phase_start(labels)[1:]
    older = np.where(start[:, 0] <= start[:, 1], 0, 1)               # the foot in contact longer
    rel = np.linalg.norm(need[:, 0] - need[:, 1], axis=-1)
    both = cont.all(axis=1)
    pinned = np.where(both, np.where(rel <= 2 * tolerance, 2, older),
                      np.where(cont[:, 0], 0, np.where(cont[:, 1], 1, -1)))
    inc = np.zeros((T - 1, 2))
    for f in (0, 1):
        inc[pinned == f] = need[pinned == f, f]
    inc[pinned == 2] = need[pinned == 2].mean(axis=1)
    shift = np.vstack([np.zeros((1, 2)), np.cumsum(inc, axis=0)])
    shift -= shift.mean(axis=0)                                      # no net drift from the solver's path
    return shift, np.concatenate([[-1], pinned])


def vertical_shift(corners: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """(T,) root z shift: the lowest sole corner on the floor in contact frames, the contact frames'
    shift interpolated elsewhere (0 without any contact), never leaving a corner below z = 0."""
    low = corners[..., 2].min(axis=(1, 2))                           # (T,)
    contact = labels.any(axis=1)
    t = np.arange(len(low))
    dz = np.interp(t, t[contact], -low[contact]) if contact.any() else np.zeros(len(low))
    return np.maximum(dz, -low)


def root_shift(corners: np.ndarray, labels: np.ndarray, fps: float, acceleration: float | None = None,
               yaw_slide: float = YAW_SLIDE, hold_yaw: bool = True) -> RootShift:
    """The root yaw and translation of the pass for sole corners ``corners`` (T, 2, 4, 3) (metres,
    world) of the final joint trajectory and contact labels ``labels`` (T, 2); ``acceleration``
    (m/s^2, None = no smoothing) the target of the optional smoothing of the shift; ``yaw_slide``
    (m/s, 0 = the held foot's yaw exact) the corner speed the heading's drift correction may cause;
    ``hold_yaw`` False: translation only (no yaw correction)."""
    labels = np.asarray(labels, dtype=bool)
    if not hold_yaw:
        return _rigid(corners, labels, fps, acceleration, np.zeros(len(labels)))
    reach = np.linalg.norm(corners[..., :2] - corners[..., :2].mean(axis=2, keepdims=True), axis=-1).max(initial=0.0)
    rate = yaw_slide / reach if reach > 0 else 0.0                     # corner speed = yaw rate * reach
    return _rigid(corners, labels, fps, acceleration, yaw_correction(corners, labels, fps, rate))


def _rigid(corners: np.ndarray, labels: np.ndarray, fps: float, acceleration: float | None,
           yaw: np.ndarray) -> RootShift:
    """The pass with the root yaw ``yaw`` (T,) given: the translation that pins the stance soles and
    keeps the floor (see the module docstring)."""
    pivot = corners[..., :2].mean(axis=(1, 2))
    corners = RootShift(np.zeros((len(labels), 3)), np.zeros(len(labels)), yaw, pivot).points(corners)
    centres = corners[..., :2].mean(axis=2)
    xy, pinned = horizontal_shift(centres, labels, SLIDE_TOLERANCE / fps)
    shift = np.column_stack([xy, vertical_shift(corners, labels)])
    if acceleration is not None and len(shift) >= 3:
        shift = _smoothed(shift, corners, centres, labels, fps, acceleration)
    return RootShift(shift, pinned, yaw, pivot)


def _smoothed(exact: np.ndarray, corners: np.ndarray, centres: np.ndarray, labels: np.ndarray,
              fps: float, acceleration: float) -> np.ndarray:
    """The shift smoothed towards ``acceleration`` where that keeps the floor (within
    FLOOR_TOLERANCE) and the stance soles' slide (within the 1 cm/s contact tolerance); the exact
    shift elsewhere."""
    smooth = smooth_to_targets(exact, np.inf, acceleration, fps)
    low = corners[..., 2].min(axis=(1, 2))
    smooth[:, 2] = np.maximum(smooth[:, 2], -low)                    # floor: exact in every frame
    cont = labels[1:] & labels[:-1]
    # whether the pair of frames (t, t+1) slides, for each choice (exact or smoothed) of the two
    # frames' shifts: slides[2 * (t exact) + (t+1 exact), t]
    moved = [centres + x[:, None, :2] for x in (smooth, exact)]         # (T, 2, 2) each
    slides = np.stack([(cont & (np.linalg.norm(moved[j][1:] - moved[i][:-1], axis=-1) * fps > SLIDE_TOLERANCE)).any(axis=1)
                       for i in (0, 1) for j in (0, 1)])                # (4, T-1)
    pairs = np.arange(len(exact) - 1)
    bad = np.zeros(len(exact), dtype=bool)
    for _ in range(len(exact)):  # grow the fallback set until no continuing contact slides
        step = slides[2 * bad[:-1] + bad[1:], pairs]
        if not step.any():
            break
        bad[1:] |= step
        bad[:-1] |= step
    return np.where(bad[:, None], exact, smooth)

"""Exact final pass that moves only the floating root (translation) so that no sole corner is below
the floor and the stance sole does not slide, without touching the joint angles (so the joint and
velocity limits, already exact, stay exact).

A pure translation ``d`` of the root translates every body, so the sole corners of frame ``t`` after
the pass are the corners before it plus ``d[t]``: the pass is closed-form and vectorised.

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
actual soles is unchanged by the translation.
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


@dataclass(frozen=True)
class RootShift:
    """``shift`` (T, 3) metres added to the root position per frame; ``pinned`` (T,) the foot
    (0 left, 1 right, 2 both: mean shift, -1 none) that fixed the horizontal shift of each frame."""

    shift: np.ndarray
    pinned: np.ndarray

    def figures(self) -> dict:
        norm = np.linalg.norm(self.shift, axis=1)
        return {"max_root_shift_m": float(norm.max()) if len(norm) else 0.0,
                "max_root_shift_z_m": float(np.abs(self.shift[:, 2]).max()) if len(norm) else 0.0,
                "root_shift_per_frame": norm.tolist()}


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


def root_shift(corners: np.ndarray, labels: np.ndarray, fps: float,
               acceleration: float | None = None) -> RootShift:
    """The root translation of the pass for sole corners ``corners`` (T, 2, 4, 3) (metres, world) of
    the final joint trajectory and contact labels ``labels`` (T, 2); ``acceleration`` (m/s^2, None =
    no smoothing) the target of the optional smoothing of the shift."""
    labels = np.asarray(labels, dtype=bool)
    tol = SLIDE_TOLERANCE / fps
    centres = corners[..., :2].mean(axis=2)
    xy, pinned = horizontal_shift(centres, labels, tol)
    shift = np.column_stack([xy, vertical_shift(corners, labels)])
    if acceleration is not None and len(shift) >= 3:
        shift = _smoothed(shift, corners, centres, labels, fps, acceleration)
    return RootShift(shift, pinned)


def _smoothed(exact: np.ndarray, corners: np.ndarray, centres: np.ndarray, labels: np.ndarray,
              fps: float, acceleration: float) -> np.ndarray:
    """The shift smoothed towards ``acceleration`` where that keeps the floor (within
    FLOOR_TOLERANCE) and the stance soles' slide (within the 1 cm/s contact tolerance); the exact
    shift elsewhere."""
    smooth = smooth_to_targets(exact, np.inf, acceleration, fps)
    low = corners[..., 2].min(axis=(1, 2))
    smooth[:, 2] = np.maximum(smooth[:, 2], -low)                    # floor: exact in every frame
    cont = labels[1:] & labels[:-1]
    out = smooth
    bad = np.zeros(len(exact), dtype=bool)
    for _ in range(len(exact)):  # grow the fallback set until no continuing contact slides
        moved = centres + out[:, None, :2]                           # (T, 2, 2)
        slide = np.linalg.norm(np.diff(moved, axis=0), axis=-1) * fps    # (T-1, 2)
        step = (cont & (slide > SLIDE_TOLERANCE)).any(axis=1)
        if not step.any():
            break
        bad[1:] |= step
        bad[:-1] |= step
        out = np.where(bad[:, None], exact, smooth)
    return out

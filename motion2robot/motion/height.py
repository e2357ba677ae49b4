"""Subject height (stature) from keypoints, in the positions' own units.

Two estimates, the larger wins:

* posture: the head keypoint's height above the lowest foot keypoint (ankles, toes) along +z,
  at the 98th percentile over frames (the most upright frames, robust to one glitched frame),
  times :data:`HEAD_TOP_FACTOR` because the SMPL head keypoint sits ~0.12 m below the top of
  the head of a 1.7 m body;
* bones: median leg length (hip-knee-ankle) plus the spine chain (pelvis-spine1-spine2-spine3-
  neck-head) times :data:`BONE_FACTOR`, which does not depend on the pose and so covers clips
  that never stand up (crouching, sitting). The factor is set so that the HumanML3D skeleton
  gives the same height both ways (1.70 m); across the development clips the two agree within
  about 8 %.
"""

from __future__ import annotations

import numpy as np

from motion2robot.motion.human import KP, HumanMotion

HEAD_TOP_FACTOR = 1.08
BONE_FACTOR = 1.15
_FEET = [KP["left_ankle"], KP["right_ankle"], KP["left_foot"], KP["right_foot"]]
_LEGS = (("left_hip", "left_knee"), ("left_knee", "left_ankle"),
         ("right_hip", "right_knee"), ("right_knee", "right_ankle"))
_SPINE = (("pelvis", "spine1"), ("spine1", "spine2"), ("spine2", "spine3"), ("spine3", "neck"),
          ("neck", "head"))


_A = np.array([KP[a] for a, _ in _LEGS + _SPINE], dtype=np.intp)
_B = np.array([KP[b] for _, b in _LEGS + _SPINE], dtype=np.intp)
if not (_B == _A + 3).all():  # pragma: no cover - guards _minus_joint_plus_3
    raise ImportError("height.py: bone table no longer pairs joint j with j + 3")
_FEET_IDX = np.array(_FEET, dtype=np.intp)
_HEAD = KP["head"]


def _minus_joint_plus_3(positions: np.ndarray) -> np.ndarray:
    """(T, J, 3) array whose [t, j] is positions[t, j] - positions[t, j + 3] for j < J - 3 (rows
    j >= J - 3 are unspecified). Every bone in _LEGS / _SPINE runs from joint j to j + 3 in SMPL22
    order, so this one flat subtraction holds them all (same values as per-bone differences)."""
    p = np.ascontiguousarray(positions)
    flat = p.reshape(-1)
    out = np.empty_like(flat)
    step = 3 * p.shape[-1]
    np.subtract(flat[:-step], flat[step:], out=out[:-step])
    out[-step:] = 0
    return out.reshape(p.shape)


def _percentile(x: np.ndarray, q: float) -> float:
    """``np.percentile(x, q)`` (method "linear") of a 1-d array, bit for bit, without the generic
    machinery: sort, then numpy's own index and interpolation arithmetic."""
    s = np.sort(x)
    n = s.shape[0]
    if n == 0 or np.isnan(s[-1]):  # numpy: NaN in -> NaN out (empty -> its own error)
        return float(np.percentile(x, q))
    virtual = (n - 1) * (q / 100)
    if virtual >= n - 1:
        return float(s[-1])
    lo = int(np.floor(virtual))
    a, b, t = float(s[lo]), float(s[lo + 1]), virtual - lo
    diff = b - a
    return b - diff * (1 - t) if t >= 0.5 else a + diff * t


def _median_axis0(x: np.ndarray) -> np.ndarray:
    """``np.median(x, axis=0)`` of a 2-d array, bit for bit (sort; mean of the middle pair)."""
    n = x.shape[0]
    if n == 0:
        return np.median(x, axis=0)
    s = np.sort(x, axis=0)
    if np.isnan(s[-1]).any():  # NaN sorts last; numpy's NaN handling
        return np.median(x, axis=0)
    k = n // 2
    if n % 2:
        return s[k]
    return (s[k - 1] + s[k]) / 2


def posture_height(positions: np.ndarray) -> float:
    """Head above the lowest foot keypoint (98th percentile over frames) x HEAD_TOP_FACTOR; z up."""
    h = positions[..., 2]
    span = h[:, _HEAD] - h[:, _FEET_IDX].min(axis=1)
    return _percentile(span, 98) * HEAD_TOP_FACTOR


def bone_height(positions: np.ndarray) -> float:
    """(Leg length + spine chain length) x BONE_FACTOR; independent of pose and axes."""
    d = _minus_joint_plus_3(positions).take(_A, axis=1)
    lengths = _median_axis0(np.sqrt(np.einsum("tbi,tbi->tb", d, d)))
    leg = lengths[: len(_LEGS)].sum() / 2.0
    spine = lengths[len(_LEGS):].sum()
    return float(leg + spine) * BONE_FACTOR


def stature(positions: np.ndarray) -> float:
    """Subject height of (T, 22, 3) z-up positions, in their units: max of the two estimates."""
    return max(posture_height(positions), bone_height(positions))


def subject_height(m: HumanMotion) -> float:
    """Subject height in metres (see the module docstring for the method)."""
    return stature(m.positions)

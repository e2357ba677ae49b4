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


_A = [KP[a] for a, _ in _LEGS + _SPINE]
_B = [KP[b] for _, b in _LEGS + _SPINE]


def posture_height(positions: np.ndarray) -> float:
    """Head above the lowest foot keypoint (98th percentile over frames) x HEAD_TOP_FACTOR; z up."""
    h = positions[..., 2]
    span = h[:, KP["head"]] - h[:, _FEET].min(axis=1)
    return float(np.percentile(span, 98)) * HEAD_TOP_FACTOR


def bone_height(positions: np.ndarray) -> float:
    """(Leg length + spine chain length) x BONE_FACTOR; independent of pose and axes."""
    d = positions[:, _A] - positions[:, _B]
    lengths = np.median(np.sqrt(np.einsum("tbi,tbi->tb", d, d)), axis=0)
    leg = lengths[: len(_LEGS)].sum() / 2.0
    spine = lengths[len(_LEGS):].sum()
    return float(leg + spine) * BONE_FACTOR


def stature(positions: np.ndarray) -> float:
    """Subject height of (T, 22, 3) z-up positions, in their units: max of the two estimates."""
    return max(posture_height(positions), bone_height(positions))


def subject_height(m: HumanMotion) -> float:
    """Subject height in metres (see the module docstring for the method)."""
    return stature(m.positions)

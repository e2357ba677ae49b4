"""The ``stance`` alternative: the legs keep a stable stance while the upper body and head perform.

For motions the robot cannot perform with its whole body (flight phases, steps it would fall
from), the human motion is rewritten before retargeting: the pelvis stays over the feet at the
clip's standing height and heading (its heading at the first frame), the legs stand straight
below the hips with the feet flat in contact in every frame, and every upper-body keypoint
(spine, neck, head, collars, arms) keeps its motion relative to the pelvis, turned into the
pelvis's own heading (so a turning walk becomes arms and torso moving in place). The result is a
quasi-static motion the whole-body pipeline handles like standing and waving.

Units: metres, canonical frame (z up, x forward at frame 0).
"""

from __future__ import annotations

import numpy as np

from motion2robot.motion.human import KP, HumanMotion

#: Leg span of the stance (hip to ankle) as a fraction of the leg's length: knees slightly bent,
#: away from the straight-knee singularity.
KNEE_SPAN = 0.96
#: Keypoints that keep their motion relative to the pelvis.
UPPER = ("spine1", "spine2", "spine3", "neck", "head", "left_collar", "right_collar", "left_shoulder",
         "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist")
_SIDES = (("left_hip", "left_knee", "left_ankle", "left_foot"), ("right_hip", "right_knee", "right_ankle", "right_foot"))


def heading(positions: np.ndarray) -> np.ndarray:
    """(T,) yaw (rad, unwrapped) of the pelvis: the direction perpendicular to the hip line, z up."""
    lr = positions[:, KP["left_hip"]] - positions[:, KP["right_hip"]]
    return np.unwrap(np.arctan2(-lr[:, 0], lr[:, 1]))  # forward = (left - right) x z


def _rot_z(yaw: np.ndarray) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    R = np.zeros(yaw.shape + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1], R[..., 2, 2] = c, -s, s, c, 1.0
    return R


def stance(human: HumanMotion) -> HumanMotion:
    """The motion with its legs replaced by a fixed double-support stance (see the module text)."""
    P = np.asarray(human.positions)
    T = len(P)
    yaw = heading(P)
    pelvis = P[:, KP["pelvis"]]
    local = np.einsum("tji,tkj->tki", _rot_z(yaw), P - pelvis[:, None, :])  # R(yaw)^T (p - pelvis)
    out = np.empty_like(P)
    # the legs: straight below the hips, feet flat ahead of the ankles, at the clip's own lengths
    ankle_z = float(np.median(np.minimum(P[:, KP["left_ankle"], 2], P[:, KP["right_ankle"], 2])))
    legs = []
    for hip, knee, ankle, foot in _SIDES:
        h = np.median(local[:, KP[hip]], axis=0)
        thigh = float(np.median(np.linalg.norm(P[:, KP[knee]] - P[:, KP[hip]], axis=1)))
        shin = float(np.median(np.linalg.norm(P[:, KP[ankle]] - P[:, KP[knee]], axis=1)))
        toe = np.median(local[:, KP[foot]] - local[:, KP[ankle]], axis=0)
        legs.append((h, thigh, shin, toe))
    height = ankle_z + min(KNEE_SPAN * (th + sh) - h[2] for h, th, sh, _ in legs)  # pelvis over the floor
    R0 = _rot_z(np.array(yaw[0]))
    base = np.array([pelvis[0, 0], pelvis[0, 1], height])
    for (hip, knee, ankle, foot), (h, thigh, shin, toe) in zip(_SIDES, legs):
        hip_p = np.array([h[0], h[1], height + h[2]])
        ankle_p = np.array([h[0], h[1], ankle_z])
        d = hip_p[2] - ankle_z  # hip straight above the ankle; the knee forward (two-link, sagittal)
        a = np.clip((thigh ** 2 - shin ** 2 + d ** 2) / (2 * d), 0.0, thigh)
        knee_p = hip_p + np.array([np.sqrt(max(thigh ** 2 - a ** 2, 0.0)), 0.0, -a])
        toe_p = ankle_p + np.array([toe[0], toe[1], min(toe[2], 0.0)])
        for name, p in ((hip, hip_p), (knee, knee_p), (ankle, ankle_p), (foot, toe_p)):
            out[:, KP[name]] = R0 @ (p - np.array([0.0, 0.0, height])) + base
    out[:, KP["pelvis"]] = base
    for name in UPPER:
        out[:, KP[name]] = local[:, KP[name]] @ R0.T + base
    return human.with_(positions=out, contacts=np.ones((T, 2), dtype=bool), meta={"legs": "stance"})


def has_flight(human: HumanMotion, labels: np.ndarray, min_frames: int = 2) -> bool:
    """True when both feet are off the floor together for ``min_frames`` or more frames between
    the first and the last contact (a run or a jump)."""
    both_off = ~labels.any(axis=1)
    idx = np.flatnonzero(labels.any(axis=1))
    if idx.size == 0:
        return True
    inner = both_off[idx[0]: idx[-1] + 1]
    run = longest = 0
    for v in inner:
        run = run + 1 if v else 0
        longest = max(longest, run)
    return longest >= min_frames

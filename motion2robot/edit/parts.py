"""Body parts: which the human edit changed (per frame), and which part drives each robot hinge.

Parts (SMPL22 indices): global = the pelvis (where the body is and which way it faces); torso
3, 6, 9, 12, 15; left arm 13, 16, 18, 20; right arm 14, 17, 19, 21; left leg 1, 4, 7, 10; right
leg 2, 5, 8, 11. A part is unedited in a frame where source and edit agree within the tolerance:
the pelvis position (and heading) for "global", the part's joints relative to the pelvis, in the
pelvis's heading frame, for the others (an edit that only moves the whole body changes "global").
"""

from __future__ import annotations

import numpy as np

from motion2robot.motion.human import KP, HumanMotion

PARTS: dict[str, tuple[int, ...]] = {
    "global": (0,), "torso": (3, 6, 9, 12, 15), "left_arm": (13, 16, 18, 20), "right_arm": (14, 17, 19, 21),
    "left_leg": (1, 4, 7, 10), "right_leg": (2, 5, 8, 11),
}
PART_OF_KEYPOINT = {kp: part for part, idx in PARTS.items() for kp in idx}
#: Default tolerance: metres of joint displacement (and its angle in radians for the heading).
TOLERANCE = 0.02


def _heading(p: np.ndarray) -> np.ndarray:
    left = p[:, KP["left_hip"]] - p[:, KP["right_hip"]]
    return np.arctan2(-left[:, 0], left[:, 1])


def _local(p: np.ndarray) -> np.ndarray:
    """(T, 22, 3) joints relative to the pelvis, rotated into the pelvis's heading frame."""
    h = _heading(p)
    c, s = np.cos(-h), np.sin(-h)
    d = p - p[:, :1]
    return np.stack([c[:, None] * d[..., 0] - s[:, None] * d[..., 1],
                     s[:, None] * d[..., 0] + c[:, None] * d[..., 1], d[..., 2]], axis=-1)


def part_deviation(source: HumanMotion, edit: HumanMotion) -> dict[str, np.ndarray]:
    """{part: (T,) largest deviation in metres} over the frames both have (same rate assumed);
    for "global" the pelvis displacement, or the heading change in radians if larger."""
    t = min(source.num_frames, edit.num_frames)
    a, b = source.positions[:t], edit.positions[:t]
    la, lb = _local(a), _local(b)
    out = {}
    for part, idx in PARTS.items():
        if part == "global":
            turn = np.abs(np.angle(np.exp(1j * (_heading(a) - _heading(b)))))
            out[part] = np.maximum(np.linalg.norm(a[:, 0] - b[:, 0], axis=-1), turn)
        else:
            out[part] = np.linalg.norm(la[:, idx] - lb[:, idx], axis=-1).max(axis=1)
    return out


def hinge_parts(robot) -> list[frozenset[str]]:
    """For each robot hinge, the part(s) driving it: those of the nearest tracked keypoints below it
    in the kinematic tree (a waist hinge below which sit the spine and both arms is torso)."""
    m = robot.model
    out = []
    for jid in robot.joint_ids:
        body = int(m.jnt_bodyid[jid])
        best: dict[int, set[str]] = {}
        for kp, site in zip(robot.keypoints, robot.keypoint_sites):
            b, depth = int(m.site_bodyid[site]), 0
            while b != body and b > 0:
                b, depth = int(m.body_parentid[b]), depth + 1
            if b == body:
                best.setdefault(depth, set()).add(PART_OF_KEYPOINT[KP[kp]])
        out.append(frozenset(best[min(best)]) if best else frozenset({"global"}))
    return out

"""Per-frame parameters of the problem (targets, contact weights, support half-planes) from the
scaled human keypoints, packed in the layout of :class:`~motion2robot.retarget.problem.ProblemSpec`."""

from __future__ import annotations

import numpy as np

from motion2robot.motion.human import KP
from motion2robot.retarget.problem import HMAX, ProblemSpec, quat_mul


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-9)


def pelvis_left(kp: np.ndarray) -> np.ndarray:
    """(T, 3) unit vector from the right hip to the left hip of (T, 22, 3) keypoints."""
    return _unit(kp[:, KP["left_hip"]] - kp[:, KP["right_hip"]])


def frame_params(spec: ProblemSpec, kp: np.ndarray, labels: np.ndarray, soles: np.ndarray | None,
                 planes: np.ndarray | None, balance: np.ndarray | None) -> np.ndarray:
    """(T, n_params) parameters.

    kp: (T, 22, 3) scaled human keypoints (robot metres, world frame). labels: (T, 2) contacts.
    soles: (T, 2, 4, 3) pinned sole corners (contact frames) or None (then only z = 0 is asked
    in contact frames). planes: (T, HMAX, 3) support half-planes; balance: (T,) bool, frames
    where the balance term is on (None = off)."""
    T = kp.shape[0]
    lay = spec.layout
    P = np.zeros((T, spec.n_params))
    idx = [KP[k] for k in spec.kp_names]
    P[:, lay["kp_t"]] = kp[:, idx].reshape(T, -1)
    P[:, lay["kp_w"]] = 1.0
    if spec.dir_pairs:
        a = np.array([idx[i] for i, _ in spec.dir_pairs])
        b = np.array([idx[j] for _, j in spec.dir_pairs])
        P[:, lay["dir_t"]] = _unit(kp[:, b] - kp[:, a]).reshape(T, -1)
        P[:, lay["dir_w"]] = 1.0
    P[:, lay["pelvis_left"]] = pelvis_left(kp)
    P[:, lay["torso_up"]] = _unit(kp[:, KP["neck"]] - kp[:, KP["spine1"]])
    fwd = np.zeros((T, 2, 3))
    wf = np.zeros((T, 2))
    for f, side in enumerate(("left", "right")):
        v = kp[:, KP[f"{side}_foot"], :2] - kp[:, KP[f"{side}_ankle"], :2]
        n = np.linalg.norm(v, axis=-1)
        fwd[:, f, :2] = v / np.maximum(n, 1e-9)[:, None]
        wf[:, f] = n > 0.02 * spec.length
    P[:, lay["foot_fwd"]] = fwd.reshape(T, -1)
    P[:, lay["foot_fwd_w"]] = wf
    if soles is not None:
        P[:, lay["sole_t"]] = np.nan_to_num(soles).reshape(T, -1)
        P[:, lay["sole_wxy"]] = labels
    P[:, lay["sole_wz"]] = labels
    P[:, lay["bal"]] = np.tile([0.0, 0.0, 1.0], HMAX)
    if planes is not None and balance is not None:
        P[:, lay["bal"]] = planes.reshape(T, -1)
        P[:, lay["bal_w"]] = np.asarray(balance, dtype=float)[:, None]
    return P


def initial_qpos(spec: ProblemSpec, kp: np.ndarray) -> np.ndarray:
    """(T, nq) start: the nominal posture, turned to the human pelvis heading and moved to the
    scaled pelvis position (root height nominal)."""
    rb = spec.robot
    T = kp.shape[0]
    left = pelvis_left(kp)
    yaw = np.arctan2(left[:, 1], left[:, 0]) - np.pi / 2
    q = np.tile(rb.nominal_qpos, (T, 1))
    half = 0.5 * yaw
    qz = np.stack([np.cos(half), np.zeros(T), np.zeros(T), np.sin(half)], -1)
    q[:, 3:7] = quat_mul(qz, q[:, 3:7])
    if "pelvis" in spec.kp_names:
        off = rb.nominal_site_xpos[rb.keypoint_sites[spec.kp_names.index("pelvis")], :2] - rb.nominal_qpos[:2]
    else:
        off = np.zeros(2)
    c, s = np.cos(yaw), np.sin(yaw)
    q[:, 0] = kp[:, KP["pelvis"], 0] - (c * off[0] - s * off[1])
    q[:, 1] = kp[:, KP["pelvis"], 1] - (s * off[0] + c * off[1])
    return q

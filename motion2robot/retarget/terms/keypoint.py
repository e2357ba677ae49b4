"""Keypoint positions vs the scaled human keypoints (per-keypoint and per-frame weighted)."""

import casadi as ca

from motion2robot.retarget.terms.base import Inputs, Term


def residual(x: Inputs) -> list:
    w, P, L = x.spec.robot.keypoint_weights, x.P, x.spec.length
    return [ca.sqrt(w[i] * P["kp_w"][i]) * (k - P["kp_t"][3 * i:3 * i + 3]) / L for i, k in enumerate(x.kp)]


TERM = Term("keypoint", 1.0, False, residual)

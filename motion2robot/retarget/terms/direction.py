"""Limb directions (hip->knee, elbow->wrist, ...) vs the human's, as unit vectors."""

import casadi as ca

from motion2robot.retarget.terms.base import Inputs, Term, unit


def residual(x: Inputs) -> list:
    return [ca.sqrt(x.P["dir_w"][d]) * (unit(x.kp[b] - x.kp[a]) - x.P["dir_t"][3 * d:3 * d + 3])
            for d, (a, b) in enumerate(x.spec.dir_pairs)]


TERM = Term("direction", 0.3, False, residual)

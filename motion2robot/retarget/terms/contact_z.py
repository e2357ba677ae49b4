"""Sole corners at their target height (the floor, or a swing's planned height) where pinned."""

import casadi as ca

from motion2robot.retarget.terms.base import Inputs, Term


def residual(x: Inputs) -> list:
    P, L = x.P, x.spec.length
    return [ca.sqrt(P["sole_wz"][c // 4]) * (p[2] - P["sole_t"][3 * c + 2]) / L for c, p in enumerate(x.corners)]


TERM = Term("contact_z", 1e5, True, residual)

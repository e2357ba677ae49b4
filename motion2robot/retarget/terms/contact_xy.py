"""Sole corners at their target xy where pinned: a planted sole neither slides nor twists."""

import casadi as ca

from motion2robot.retarget.terms.base import Inputs, Term


def residual(x: Inputs) -> list:
    P, L = x.P, x.spec.length
    return [ca.sqrt(P["sole_wxy"][c // 4]) * (p[0:2] - P["sole_t"][3 * c:3 * c + 2]) / L for c, p in enumerate(x.corners)]


TERM = Term("contact_xy", 1e5, True, residual)

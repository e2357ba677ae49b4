"""No sole corner below z = 0 (a hinge: zero above the floor), every frame."""

import casadi as ca

from motion2robot.retarget.terms.base import Inputs, Term


def residual(x: Inputs) -> list:
    return [ca.fmin(p[2], 0) / x.spec.length for p in x.corners]


TERM = Term("floor", 1e5, True, residual)

"""Limb capsules vs torso / other leg: distance >= sum of radii (a hinge); bodies at most two
hinges apart through the joint-space cuts of :mod:`~motion2robot.retarget.joint_cuts` (linear)."""

import casadi as ca

from motion2robot.retarget.terms.base import Inputs, Term


def residual(x: Inputs) -> list:
    return [ca.fmin(g, 0) / x.spec.length for g in x.gaps]


TERM = Term("self_collision", 1e6, True, residual)

"""Hinge angles vs the nominal posture (rad): picks one of equally good solutions."""

import casadi as ca

from motion2robot.retarget.terms.base import Inputs, Term


def residual(x: Inputs) -> list:
    return [x.q[7:] + x.dx[6:] - ca.DM(x.spec.robot.nominal_qpos[7:])]


TERM = Term("posture", 2e-3, False, residual)

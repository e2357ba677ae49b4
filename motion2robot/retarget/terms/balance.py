"""The CoM's ground projection inside the shrunk support polygon: the most violated of its
half-planes n . c <= b (a hinge), weighted per frame."""

import casadi as ca

from motion2robot.retarget.terms.base import Inputs, Term

#: Maximum number of support-polygon half-planes per frame.
HMAX = 8


def residual(x: Inputs) -> list:
    bal, com = x.P["bal"], x.com
    worst = bal[0] * com[0] + bal[1] * com[1] - bal[2]
    for h in range(1, HMAX):
        worst = ca.fmax(worst, bal[3 * h] * com[0] + bal[3 * h + 1] * com[1] - bal[3 * h + 2])
    return [ca.sqrt(x.P["bal_w"]) * ca.fmax(0, worst) / x.spec.length]


TERM = Term("balance", 1e5, True, residual)

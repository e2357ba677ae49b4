"""Each foot's forward axis vs the human ankle->toe direction (horizontal components)."""

import casadi as ca

from motion2robot.retarget.terms.base import Inputs, Term


def residual(x: Inputs) -> list:
    out = []
    for f, body in enumerate(x.spec.robot.foot_bodies):
        fwd = x.tf.vector(int(body), x.spec.foot_fwd_local[f])
        out.append(ca.sqrt(x.P["foot_fwd_w"][f]) * (fwd[0:2] - x.P["foot_fwd"][3 * f:3 * f + 2]))
    return out


TERM = Term("foot_heading", 0.05, False, residual)

"""Each sole's normal vs world up (its horizontal components)."""

from motion2robot.retarget.terms.base import Inputs, Term


def residual(x: Inputs) -> list:
    return [x.tf.vector(int(body), x.spec.foot_up_local[f])[0:2] for f, body in enumerate(x.spec.robot.foot_bodies)]


TERM = Term("sole_flat", 0.05, False, residual)

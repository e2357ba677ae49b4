"""The root body's left axis vs the human pelvis left axis (the hips line)."""

from motion2robot.retarget.terms.base import Inputs, Term


def residual(x: Inputs) -> list:
    return [x.tf.vector(x.spec.robot.root_body, x.spec.left_local) - x.P["pelvis_left"]]


TERM = Term("pelvis_heading", 0.1, False, residual)

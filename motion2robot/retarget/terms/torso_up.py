"""The torso body's up axis vs the human spine direction."""

from motion2robot.retarget.terms.base import Inputs, Term


def residual(x: Inputs) -> list:
    return [x.tf.vector(x.spec.robot.torso_body, x.spec.torso_up_local) - x.P["torso_up"]]


TERM = Term("torso_up", 0.05, False, residual)

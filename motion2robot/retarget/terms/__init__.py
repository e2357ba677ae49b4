"""The registry of the retargeting problem's cost terms: one module per term, one line here.

Order is the compiled function's weight-vector order. To add a term: a module with a ``TERM``
(:class:`~motion2robot.retarget.terms.base.Term`) and its line below (new frame parameters also
go into the layout of :mod:`~motion2robot.retarget.problem`).
"""

from motion2robot.retarget.terms import (
    balance,
    contact_xy,
    contact_z,
    direction,
    floor,
    foot_heading,
    keypoint,
    pelvis_heading,
    posture,
    self_collision,
    sole_flat,
    torso_up,
)
from motion2robot.retarget.terms.base import Inputs, Term

TERMS: tuple[Term, ...] = (
    keypoint.TERM,
    direction.TERM,
    pelvis_heading.TERM,
    torso_up.TERM,
    foot_heading.TERM,
    sole_flat.TERM,
    posture.TERM,
    contact_z.TERM,
    contact_xy.TERM,
    floor.TERM,
    balance.TERM,
    self_collision.TERM,
)

__all__ = ["TERMS", "Inputs", "Term"]

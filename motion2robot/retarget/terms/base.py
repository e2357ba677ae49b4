"""What a cost term of the retargeting problem is, and what its residual is computed from.

A :class:`Term` declares its name, its default weight, whether it is a hard constraint (its
unweighted rows are zero when satisfied; the projection drives them to zero) and a residual
function of :class:`Inputs` returning casadi SX rows. Position residuals are divided by the
robot's leg length (so weights do not depend on the robot's size); direction and axis residuals
are differences of unit vectors; joint residuals are radians. Cost = weight * ||rows||^2.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import casadi as ca


class Inputs(NamedTuple):
    """spec: the ProblemSpec; P: frame parameters by layout name (SX slices); tf: tangent frames
    at the configuration; kp: keypoint positions; corners: sole corners (left 4, right 4); com:
    centre of mass; gaps: self-collision clearances (m, >= 0 when clear); q, dx: configuration and
    tangent step."""

    spec: Any
    P: dict
    tf: Any
    kp: list
    corners: list
    com: Any
    gaps: list
    q: Any
    dx: Any


@dataclass(frozen=True)
class Term:
    """name: the term's key (weights, reports); weight: default weight; hard: a hard constraint;
    residual: rows (list of SX) from :class:`Inputs`."""

    name: str
    weight: float
    hard: bool
    residual: Callable[[Inputs], list]


def unit(v):
    """v / |v| (SX), safe at zero."""
    return v / ca.sqrt(ca.sumsqr(v) + 1e-12)

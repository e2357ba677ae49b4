"""Tempo: playing a human motion slower (or faster) before it is retargeted.

A tempo factor k >= ... stretches time: the motion's durations are multiplied by k (k = 1: as
generated; k = 2: twice as slow), the frame rate is kept, so a clip of T frames becomes
round((T - 1) * k) + 1 frames. Positions are interpolated with natural cubic splines through the
original samples (:func:`~motion2robot.motion.ops.spline`, C2); contact labels take the nearest
original frame. Joint speeds fall by 1/k and accelerations (hence inertial torques and the ZMP's
offset from the CoM, (z_c / g) c'') by 1/k^2.

Policies (``--tempo``): ``human`` keeps the generated timing; ``similar`` plays the motion
dynamically similar for the robot's size (Froude number v^2 / (g L) kept: durations x sqrt(s)
with s the robot/human leg-length ratio; for a small robot that is *faster* than the human, since
at the human's tempo a scaled-down motion asks for accelerations s times smaller relative to
gravity); ``auto`` the smallest slow-down from :func:`auto_factors` that passes ``check``; a number
is the factor itself.
"""

from __future__ import annotations

import math

import numpy as np

from motion2robot.errors import UserError
from motion2robot.motion.human import HumanMotion
from motion2robot.motion.ops import spline

#: Default cap of the ``auto`` policy.
DEFAULT_CAP = 2.5
#: Factors tried by ``auto`` below the cap (the cap itself is tried last).
AUTO_STEPS = (1.0, 1.25, 1.6, 2.0)
#: Slowest and fastest factor accepted from the command line.
MIN_FACTOR, MAX_FACTOR = 0.25, 10.0


def parse_tempo(value: str | float) -> str | float:
    """'human' | 'similar' | 'auto' | a factor in [MIN_FACTOR, MAX_FACTOR]; a UserError otherwise."""
    if isinstance(value, str) and value.strip().lower() in ("human", "similar", "auto"):
        return value.strip().lower()
    try:
        k = float(value)
    except (TypeError, ValueError):
        raise UserError(f"--tempo {value!r}: give human, similar, auto or a slow-down factor such as 1.5") from None
    if not (math.isfinite(k) and MIN_FACTOR <= k <= MAX_FACTOR):
        raise UserError(f"--tempo {value!r}: a factor must be a number from {MIN_FACTOR} to {MAX_FACTOR} "
                        "(1 = as generated, 2 = twice as slow)")
    return k


def parse_cap(value: str | float) -> float:
    """A tempo cap >= 1 (the slowest ``auto`` may go)."""
    try:
        k = float(value)
    except (TypeError, ValueError):
        k = float("nan")
    if not (math.isfinite(k) and 1.0 <= k <= MAX_FACTOR):
        raise UserError(f"--tempo-cap {value!r}: give a number from 1 to {MAX_FACTOR} (the slowest tempo auto may choose)")
    return k


def similar_factor(leg_scale: float) -> float:
    """Dynamically similar tempo factor for a robot/human leg-length ratio: sqrt(s)."""
    return float(math.sqrt(max(leg_scale, 1e-6)))


def auto_factors(cap: float) -> list[float]:
    """Factors ``auto`` tries, slowest last: the steps below the cap, then the cap."""
    return [k for k in AUTO_STEPS if k < cap - 1e-9] + [float(cap)]


def stretch(human: HumanMotion, factor: float) -> HumanMotion:
    """The motion played ``factor`` times slower at the same frame rate (see the module text)."""
    if abs(factor - 1.0) < 1e-12:
        return human
    T = human.num_frames
    n = max(2, int(round((T - 1) * factor)) + 1)
    u = np.minimum(np.arange(n) / factor, T - 1)
    pos = spline(human.positions, u)
    contacts = None if human.contacts is None else human.contacts[np.clip(np.rint(u).astype(int), 0, T - 1)]
    return human.with_(positions=pos, contacts=contacts, meta={"tempo": float(factor)})

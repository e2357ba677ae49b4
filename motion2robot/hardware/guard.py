"""The safety guard: the one place holding every rule about what may reach a servo.

Rules (all in servo ticks, so what is checked is exactly what goes on the wire):
- a goal is inside the joint limits, rounded inwards to whole ticks;
- a goal moves no faster than the joint velocity limit (``ramp=True``: the slower ramp speed).
  The speed is ``rate = v * ticks_per_rad / rate_hz`` ticks per control tick, usually not a
  whole number: each joint earns ``rate`` ticks of budget per control tick (capped at
  ``rate + 1``) and a move spends whole ticks of it. So over any ``n`` control ticks a goal moves
  at most ``rate + 1 + rate * (n - 1) = rate * n + 1`` ticks: the limit times the
  elapsed time plus at most one tick of quantisation, never accumulating; on average exactly the
  limit. A limit below one tick per control tick (0.05 rad/s at 100 Hz is 0.33 ticks) moves one
  tick every ``1 / rate`` control ticks;
- a NaN/inf target holds that joint at its previous goal;
- start is refused if the present pose is missing/non-finite, outside the limits by more than
  one step, or a servo reports an Alert / hardware error (:meth:`SafetyGuard.start`);
- any Alert during streaming is a fault (:meth:`SafetyGuard.check_status`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from motion2robot.hardware.calibration import Calibration
from motion2robot.hardware.errors import SafetyError
from motion2robot.hardware.limits import JointLimits


class SafetyGuard:
    """Limits in ticks for the calibration's joints at ``rate_hz`` control ticks per second.

    ``limits`` must be in the calibration's joint order; ``ramp_speed`` rad/s (capped by each
    joint's velocity limit) is used for ramp-in and ramp-out."""

    def __init__(self, limits: JointLimits, calibration: Calibration, rate_hz: float, ramp_speed: float = 0.5):
        if tuple(limits.names) != calibration.joints:
            raise ValueError("guard: limits and calibration must list the same joints in the same order")
        if not (rate_hz > 0 and ramp_speed > 0):
            raise ValueError("guard: rate and ramp speed must be > 0")
        self.cal = calibration
        self.names = calibration.joints
        a, b = calibration.ticks_float(limits.lower), calibration.ticks_float(limits.upper)
        self.lo = np.ceil(np.minimum(a, b) - 1e-9).astype(np.int64)
        self.hi = np.floor(np.maximum(a, b) + 1e-9).astype(np.int64)
        k = calibration.ticks_per_rad / rate_hz
        self.rate_max = np.asarray(limits.velocity, dtype=np.float64) * k  # ticks per control tick
        self.rate_ramp = np.minimum(ramp_speed, limits.velocity) * k
        self.step_max = (np.floor(self.rate_max) + 1).astype(np.int64)  # most ticks in one control tick
        self.step_ramp = (np.floor(self.rate_ramp) + 1).astype(np.int64)
        self.budget = np.zeros(self.rate_max.shape)  # ticks each joint may still move (fractional)
        self.last: np.ndarray | None = None

    def _who(self, i: int) -> str:
        return f"servo {int(self.cal.ids[i])} ({self.names[i]})"

    def start(self, present: np.ndarray) -> np.ndarray:
        """Accept the present pose (ticks) as the first goal, or refuse with SafetyError."""
        present = np.asarray(present, dtype=np.float64)
        if present.shape != self.lo.shape or not np.all(np.isfinite(present)):
            raise SafetyError("refusing to start: the present pose could not be read completely")
        out = np.where(present < self.lo - self.step_max)[0].tolist() + np.where(present > self.hi + self.step_max)[0].tolist()
        if out:
            i = out[0]
            q = float(self.cal.to_radians(present)[i])
            raise SafetyError(f"refusing to start: {self._who(i)} is at {q:.3f} rad, outside its limits; "
                              "move it into range by hand with torque off, or check the calibration", int(self.cal.ids[i]))
        self.last = np.clip(present.astype(np.int64), self.lo, self.hi)
        self.budget = np.zeros(self.rate_max.shape)
        return self.last.copy()

    def next_goal(self, target: np.ndarray | None, ramp: bool = False) -> np.ndarray:
        """Goal ticks for this tick towards ``target`` (rad; None = hold)."""
        if self.last is None:
            raise RuntimeError("guard: start() first")
        rate = self.rate_ramp if ramp else self.rate_max
        self.budget = np.minimum(self.budget + rate, rate + 1.0)
        if target is None:
            return self.last.copy()
        t = self.cal.ticks_float(np.asarray(target, dtype=np.float64))
        bad = ~np.isfinite(t)
        t = np.where(bad, self.last, np.clip(np.rint(np.where(bad, 0.0, t)), self.lo, self.hi)).astype(np.int64)
        step = np.floor(self.budget).astype(np.int64)
        goal = np.clip(self.last + np.clip(t - self.last, -step, step), self.lo, self.hi)
        self.budget -= np.abs(goal - self.last)
        self.last = goal
        return goal.copy()

    def goals(self, targets: np.ndarray) -> np.ndarray:
        """Goal ticks (K, n) int64 for K consecutive control ticks towards ``targets`` (K, n) rad:
        the goals of K calls of :meth:`next_goal` (at the velocity limit, not the ramp speed), and
        the guard left as they would leave it.
        Where every move is at most the whole ticks a control tick earns (floor of the rate: the
        budget never binds, since it is at least the rate after every earning) and every target
        is finite, each goal is its target rounded and clipped, computed at once; otherwise tick
        by tick."""
        if self.last is None:
            raise RuntimeError("guard: start() first")
        targets = np.asarray(targets, dtype=np.float64)
        if not len(targets):
            return np.zeros((0, len(self.lo)), dtype=np.int64)
        t = self.cal.ticks_float(targets)
        if np.all(np.isfinite(t)):
            goal = np.clip(np.rint(t), self.lo, self.hi).astype(np.int64)
            move = np.abs(np.diff(goal, axis=0, prepend=self.last[None]))
            if np.all(move <= np.floor(self.rate_max)):
                cap, budget = self.rate_max + 1.0, self.budget
                for m in move:  # the budget as next_goal keeps it, to the last bit
                    budget = np.minimum(budget + self.rate_max, cap)
                    budget -= m
                self.budget, self.last = budget, goal[-1].copy()
                return goal
        return np.array([self.next_goal(row) for row in targets], dtype=np.int64)

    def reached(self, target: np.ndarray) -> bool:
        """True when the last goal equals the (limited) target in ticks."""
        t = self.cal.ticks_float(np.asarray(target, dtype=np.float64))
        t = np.where(np.isfinite(t), t, self.last)
        return bool(np.all(np.clip(np.rint(t), self.lo, self.hi).astype(np.int64) == self.last))

    def check_status(self, status: Mapping[int, int], ids: Sequence[int]) -> list[int]:
        """IDs whose status byte carries the Alert bit (a fault: the caller stops)."""
        return [i for i in ids if status.get(i, 0) & 0x80]

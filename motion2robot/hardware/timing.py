"""Fixed-rate scheduling on absolute deadlines and loop timing figures."""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # typing.Self is Python 3.11+
    from typing import Self

clock = time.perf_counter


#: Longest single OS sleep: a signal handler sets a flag that is looked at between slices.
SLEEP_SLICE_S = 0.02


def sleep_until(deadline: float, spin_s: float = 0.0002, interrupted: Callable[[], bool] | None = None,
                slice_s: float = SLEEP_SLICE_S) -> bool:
    """Sleep until ``deadline`` (``clock()`` seconds): OS sleep in slices of at most ``slice_s``,
    then a short spin for precision. Returns False as soon as ``interrupted()`` is true (tested
    between slices, so within ``slice_s`` of a signal), True at the deadline."""
    while True:
        if interrupted is not None and interrupted():
            return False
        rem = deadline - clock()
        if rem <= 0:
            return True
        if rem > spin_s:
            time.sleep(min(rem - spin_s, slice_s))


@dataclass(frozen=True)
class LoopFigures:
    """Achieved loop timing. Periods are between consecutive tick starts; jitter = |period - nominal|."""

    ticks: int
    nominal_s: float
    achieved_hz: float
    period_p50_ms: float
    period_p99_ms: float
    period_max_ms: float
    jitter_p50_ms: float
    jitter_p99_ms: float
    jitter_max_ms: float
    overruns: int

    @classmethod
    def from_starts(cls, starts: Sequence[float], nominal_s: float, overruns: int) -> LoopFigures:
        s = np.asarray(starts, dtype=np.float64)
        if s.size < 2:
            return cls(int(s.size), nominal_s, 0.0, *([float("nan")] * 6), overruns)
        p = np.diff(s)
        j = np.abs(p - nominal_s)
        ms = lambda a, q: float(np.percentile(a, q) * 1e3)
        return cls(int(s.size), nominal_s, float((s.size - 1) / (s[-1] - s[0])),
                   ms(p, 50), ms(p, 99), float(p.max() * 1e3), ms(j, 50), ms(j, 99), float(j.max() * 1e3), overruns)

    def describe(self) -> str:
        return (f"{self.ticks} ticks at {self.achieved_hz:.1f} Hz (target {1 / self.nominal_s:.1f} Hz); "
                f"period p50 {self.period_p50_ms:.3f} ms, p99 {self.period_p99_ms:.3f} ms, max {self.period_max_ms:.3f} ms; "
                f"jitter p99 {self.jitter_p99_ms:.3f} ms, max {self.jitter_max_ms:.3f} ms; overruns {self.overruns}")


class realtime_priority:
    """Context manager: run this process under SCHED_FIFO at ``priority`` if the OS allows
    (root or CAP_SYS_NICE), restoring the previous policy on exit. ``granted`` says if it worked."""

    def __init__(self, enabled: bool = True, priority: int = 50):
        self.enabled = enabled
        self.priority = priority
        self.granted = False
        self._old: tuple[int, Any] | None = None

    def __enter__(self) -> Self:
        if self.enabled and hasattr(os, "sched_setscheduler"):
            try:
                self._old = (os.sched_getscheduler(0), os.sched_getparam(0))
                os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(self.priority))
                self.granted = True
            except (OSError, PermissionError):
                self._old = None
        return self

    def __exit__(self, *exc: object) -> None:
        if self._old is not None:
            try:
                os.sched_setscheduler(0, self._old[0], self._old[1])
            except OSError:
                pass

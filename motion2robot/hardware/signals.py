"""Ctrl-C and SIGTERM while streaming: they set a flag that the loop polls, never raise mid-packet.

The loop sleeps in short slices (:func:`~motion2robot.hardware.timing.sleep_until` with an
``interrupted`` test), so a signal acts within one slice whatever the control rate.
"""

from __future__ import annotations

import signal
import threading
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # typing.Self is Python 3.11+
    from typing import Self


class StopSignals:
    """Context manager: SIGINT/SIGTERM increment :attr:`count` (main thread only; elsewhere the
    handlers are left alone)."""

    def __init__(self) -> None:
        self.count = 0
        self._old: dict[int, Any] = {}

    def _handler(self, signum: int, frame: Any) -> None:
        self.count += 1

    def __enter__(self) -> Self:
        if threading.current_thread() is threading.main_thread():
            for s in (signal.SIGINT, signal.SIGTERM):
                self._old[s] = signal.signal(s, self._handler)
        return self

    def __exit__(self, *exc: object) -> None:
        for s, h in self._old.items():
            signal.signal(s, h)

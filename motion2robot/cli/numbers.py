"""Numeric command-line options checked when they are parsed: finite, in range, unit named.

``number("Hz", 0, 1000, low_open=True)`` is an argparse ``type=``: a value that is not a number,
not finite, or out of range is an argparse error, which the CLI prints as one line
``motion2robot: error: argument --rate: ...`` with exit code 2.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable


def number(unit: str, low: float, high: float, *, low_open: bool = False, whole: bool = False) -> Callable[[str], float]:
    """Parser of one value in ``unit`` within [low, high] (``(low, high]`` if ``low_open``);
    ``whole``: an integer (returned as int)."""
    span = f"{'(' if low_open else '['}{low:g}, {high:g}]"
    kind = "a whole number" if whole else "a finite number"

    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            v = math.nan
        ok = math.isfinite(v) and (v > low if low_open else v >= low) and v <= high and (not whole or v == int(v))
        if not ok:
            raise argparse.ArgumentTypeError(f"must be {kind} of {unit} in {span}, got '{text}'")
        return int(v) if whole else v

    parse.__name__ = unit  # argparse names the type in some messages
    return parse


RATE_HZ = number("Hz", 0.0, 1000.0, low_open=True)
FPS = number("frames per second", 0.1, 10000.0)
SECONDS = number("s", 0.0, 1e7, low_open=True)
RAD_PER_S = number("rad/s", 0.0, 100.0, low_open=True)
RADIANS = number("rad", 0.0, 2 * math.pi, low_open=True)
WATCHDOG_MS = number("ms", 0, 2540, whole=True)
LATENCY_MS = number("ms", 0.0, 1000.0)
BAUD = number("bit/s", 9600, 10_500_000, whole=True)
SERVO_ID = number("servo ID", 0, 252, whole=True)

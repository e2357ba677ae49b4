"""The Bus Watchdog and the control rate must agree.

A Dynamixel's Bus Watchdog (register 98, 20 ms units, 1..127) stops the servo when the bus has
been silent longer than its value while torque is on; from then on the servo refuses goals until
the register is written back to 0. Between two control ticks the bus is silent for about one
control period, so a watchdog shorter than the period trips on every tick (``--rate 5`` with the
100 ms default froze the servos after the first tick).

Rule: the watchdog must cover two control periods plus 20 ms (one late wake-up and one register
unit of slack). Left unset, it is set to the larger of 100 ms and that minimum; set by the user
below it, streaming is refused; a rate too low for the largest watchdog (2,540 ms, i.e. below
about 0.8 Hz) is refused unless the watchdog is turned off explicitly (``watchdog_ms = 0``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from motion2robot.errors import UserError

UNIT_MS = 20
MAX_MS = 127 * UNIT_MS
DEFAULT_MS = 100


def min_watchdog_ms(rate_hz: float) -> int:
    """Shortest Bus Watchdog (ms, a multiple of 20) that survives the silence between ticks at
    ``rate_hz``: two control periods plus 20 ms, rounded up to the register's unit."""
    need = 2.0 * 1000.0 / rate_hz + UNIT_MS
    return int(math.ceil(need / UNIT_MS - 1e-9)) * UNIT_MS


@dataclass(frozen=True)
class WatchdogSetting:
    """``ms``: the Bus Watchdog to arm (0 = off); ``note``: what was decided and why, for the user
    (empty when the requested value is used as is)."""

    ms: int
    note: str = ""


def watchdog_for_rate(requested_ms: int | None, rate_hz: float) -> WatchdogSetting:
    """Decide the Bus Watchdog for ``rate_hz`` (Hz): ``requested_ms`` None = choose it, 0 = off
    (accepted at any rate), else checked against :func:`min_watchdog_ms`. Raises UserError."""
    need = min_watchdog_ms(rate_hz)
    if requested_ms == 0:
        return WatchdogSetting(0, "Bus Watchdog off: if this process hangs, the servos hold their last goal")
    if need > MAX_MS:
        raise UserError(f"--rate {rate_hz:g} Hz is too slow for the Bus Watchdog: the bus would be silent "
                        f"{1000.0 / rate_hz:.0f} ms between ticks, longer than the longest watchdog ({MAX_MS} ms); "
                        f"use --rate >= {2000.0 / (MAX_MS - UNIT_MS):.2f} Hz, or --watchdog-ms 0 to stream "
                        "without a watchdog")
    if requested_ms is None:
        ms = max(DEFAULT_MS, need)
        note = "" if ms == DEFAULT_MS else (f"Bus Watchdog set to {ms} ms for {rate_hz:g} Hz "
                                            f"(two control periods + {UNIT_MS} ms; {DEFAULT_MS} ms would trip "
                                            "between ticks)")
        return WatchdogSetting(ms, note)
    if requested_ms < need:
        raise UserError(f"--watchdog-ms {requested_ms} is too short for --rate {rate_hz:g} Hz: the servos would "
                        f"stop between ticks; use --watchdog-ms >= {need} (two control periods + {UNIT_MS} ms), "
                        "a higher --rate, or leave --watchdog-ms unset to have it chosen")
    return WatchdogSetting(int(requested_ms))

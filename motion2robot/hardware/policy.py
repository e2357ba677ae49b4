"""Torque policy: what happens to the servos when streaming ends, is interrupted or faults.

Each of ``on_end``, ``on_interrupt``, ``on_fault`` is a hold time in seconds: the servos keep
their last goal (the bus is still read every tick, so a fault during the hold is seen) for that
long, then torque goes off; 0 means torque off at once. Torque always goes off in the end and
the port is always closed. ``watchdog_ms`` sets the Bus Watchdog (20 ms units, 0 = off, None =
chosen from the control rate, see :mod:`motion2robot.hardware.watchdog`) so servos stop by
themselves if this process hangs. ``ramp_speed`` (rad/s) is the speed of the
ramp from the present pose to the first frame, and of the ramp out to the rest pose at the
end when ``ramp_out`` is on.

Text form (CLI ``--policy`` or a TOML file with the same keys)::

    on_end = "hold:2"      # or "off", or a number of seconds
    on_interrupt = "off"
    on_fault = "off"
    watchdog_ms = 100      # leave out to have it chosen from the rate
    ramp_speed = 0.5
    ramp_out = true
"""

from __future__ import annotations

from collections.abc import Mapping
import math
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

from motion2robot.errors import InputFileError, UserError
from motion2robot.hardware.watchdog import DEFAULT_MS, MAX_MS, watchdog_for_rate

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]


@dataclass(frozen=True)
class TorquePolicy:
    on_end: float = 1.0
    on_interrupt: float = 0.0
    on_fault: float = 0.0
    watchdog_ms: int | None = None  # None: chosen from the control rate (for_rate)
    ramp_speed: float = 0.5
    ramp_out: bool = True

    def __post_init__(self) -> None:
        for name in ("on_end", "on_interrupt", "on_fault"):
            v = float(getattr(self, name))
            if not 0.0 <= v <= 60.0:
                raise UserError(f"torque policy: {name} must be 'off' or 'hold:N' with 0 <= N <= 60 s, got {v}")
            object.__setattr__(self, name, v)
        if self.watchdog_ms is not None and not (float(self.watchdog_ms) == int(self.watchdog_ms)
                                                 and 0 <= int(self.watchdog_ms) <= MAX_MS):
            raise UserError(f"torque policy: watchdog_ms must be a whole number of ms in 0..{MAX_MS}, "
                            f"got {self.watchdog_ms}")
        if not (math.isfinite(float(self.ramp_speed)) and 0 < float(self.ramp_speed) <= 100):
            raise UserError(f"torque policy: ramp_speed must be a finite speed in (0, 100] rad/s, got {self.ramp_speed}")

    @property
    def watchdog_units(self) -> int:
        """Bus Watchdog register value (20 ms units, rounded up; 0 = disabled; unset: 100 ms)."""
        ms = DEFAULT_MS if self.watchdog_ms is None else int(self.watchdog_ms)
        return -(-ms // 20)

    def for_rate(self, rate_hz: float) -> tuple[TorquePolicy, str]:
        """This policy with the Bus Watchdog decided for ``rate_hz`` (chosen if unset, refused with
        UserError if too short), and a note for the user saying what was decided (or "")."""
        w = watchdog_for_rate(None if self.watchdog_ms is None else int(self.watchdog_ms), rate_hz)
        return replace(self, watchdog_ms=w.ms), w.note

    @classmethod
    def from_mapping(cls, items: Mapping[str, Any], base: TorquePolicy | None = None) -> TorquePolicy:
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(items) - known)
        if unknown:
            raise UserError(f"torque policy: unknown keys {', '.join(unknown)}; use {', '.join(sorted(known))}")
        parsed: dict[str, Any] = {}
        for k, v in items.items():
            if k.startswith("on_"):
                parsed[k] = _hold_seconds(k, v)
            elif k == "ramp_out":
                parsed[k] = v if isinstance(v, bool) else str(v).lower() in ("1", "true", "yes", "on")
            elif k == "watchdog_ms":
                parsed[k] = _number(k, v, "ms", whole=True)
            else:
                parsed[k] = _number(k, v, "rad/s")
        return replace(base or cls(), **parsed)

    @classmethod
    def parse(cls, text: str, base: TorquePolicy | None = None) -> TorquePolicy:
        """From ``"on_end=hold:2,on_fault=off,watchdog_ms=100"`` or a TOML file path."""
        p = Path(text)
        if text.endswith(".toml") or p.is_file():
            try:
                return cls.from_mapping(tomllib.loads(p.read_text()), base)
            except (OSError, tomllib.TOMLDecodeError) as err:
                raise InputFileError(f"{p}: cannot read the torque policy ({err})") from err
        items = {}
        for part in filter(None, (s.strip() for s in text.split(","))):
            if "=" not in part:
                raise UserError(f"torque policy: '{part}' is not key=value (e.g. on_end=hold:2)")
            k, v = part.split("=", 1)
            items[k.strip()] = v.strip()
        return cls.from_mapping(items, base)

    def describe(self) -> str:
        f = lambda s: "torque off at once" if s == 0 else f"hold {s:g} s then torque off"
        wd = f"Bus Watchdog {self.watchdog_units * 20} ms" if self.watchdog_units else "Bus Watchdog off"
        return (f"end: {f(self.on_end)}; Ctrl-C: {f(self.on_interrupt)}; fault: {f(self.on_fault)}; {wd}; "
                f"ramps at {self.ramp_speed:g} rad/s")


def _number(key: str, value: Any, unit: str, whole: bool = False) -> Any:
    """A finite number (a whole one if ``whole``) from a TOML value or text, else UserError."""
    try:
        v = float(value) if not isinstance(value, bool) else math.nan
    except (TypeError, ValueError):
        v = math.nan
    if not math.isfinite(v) or (whole and v != int(v)):
        kind = "a whole number of" if whole else "a finite number of"
        raise UserError(f"torque policy: {key} must be {kind} {unit}, got '{value}'")
    return int(v) if whole else v


def _hold_seconds(key: str, value: Any) -> float:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        v = float(value)
    else:
        s = str(value).strip().lower()
        if s in ("off", "0"):
            return 0.0
        s = s.removeprefix("hold:")
        try:
            v = float(s.rstrip("s"))
        except ValueError:
            v = math.nan
    if not math.isfinite(v):
        raise UserError(f"torque policy: {key} must be 'off' or 'hold:SECONDS' (0 to 60 s), got '{value}'")
    return v

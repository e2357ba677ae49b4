"""The outcome of a streaming session (what the CLI prints and the demo shows)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from motion2robot.hardware.timing import LoopFigures


@dataclass(frozen=True)
class StreamReport:
    """What happened: loop figures, stop reason (end | interrupt | fault | refused), faults
    (one-line messages) and the first one's kind, per-servo torque after the stop (True/False,
    None = unknown)."""

    figures: LoopFigures
    stop_reason: str
    faults: tuple[str, ...]
    torque_after: Mapping[int, bool | None]
    telemetry_path: str | None
    dry_run: bool
    stop_tick: int
    fault_tick: int | None = None
    torque_off_errors: tuple[str, ...] = field(default_factory=tuple)
    recovered: int = 0  # bus failures recovered by a bounded retry (see telemetry events)
    fault_kind: str | None = None  # first fault's kind: watchdog, divergence, hardware_error, comm, port, ...
    watchdog_note: str = ""  # how the Bus Watchdog was chosen for the rate, when it was

    @property
    def ticks(self) -> int:
        return self.figures.ticks

    @property
    def all_torque_off(self) -> bool:
        return all(v is False for v in self.torque_after.values())

    def describe(self) -> str:
        lines = [f"stream: {self.stop_reason}" + (" (dry run)" if self.dry_run else ""), "loop: " + self.figures.describe()]
        if self.watchdog_note:
            lines.append(self.watchdog_note)
        lines += [f"fault ({self.fault_kind}): {f}" for f in self.faults]
        if self.recovered:
            lines.append(f"bus: {self.recovered} failed transfers recovered by retry (see telemetry)")
        if self.torque_after:
            on = [i for i, v in self.torque_after.items() if v]
            unknown = [i for i, v in self.torque_after.items() if v is None]
            state = "torque off on all servos" if not on and not unknown else \
                f"torque ON: {on or '-'}; torque unknown: {unknown or '-'}"
            lines.append(f"servos: {state}")
        lines += [f"torque-off error: {e}" for e in self.torque_off_errors]
        if self.telemetry_path:
            lines.append(f"telemetry: {self.telemetry_path}")
        return "\n".join(lines)

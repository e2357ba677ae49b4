"""Streaming telemetry as JSON Lines, flushed line by line so it is readable if the process dies.

Records (one JSON object per line, ``"type"`` first):
- ``header``: joints, servo IDs, rate, policy, motion, start time (Unix s);
- ``tick``: ``i`` tick index, ``t`` seconds since start, ``period`` and ``late`` (s), ``phase``
  (ramp_in, play, ramp_out, hold), ``cmd`` commanded goal (rad per joint), ``present`` (rad per
  joint or null in a dry run);
- ``event``: faults, retries, warnings (``kind``, ``message``, ``servo``);
- ``stop``: reason (end, interrupt, fault), tick, per-servo torque state after the stop, errors,
  loop figures. A file without ``stop`` means the process died mid-stream.
"""

from __future__ import annotations

import json
import math
import queue
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from motion2robot.errors import InputFileError


def _r(values: Sequence[float] | None, nd: int = 5) -> list[float | None] | None:
    if values is None:
        return None
    return [round(float(v), nd) if math.isfinite(v) else None for v in values]


def _finite(obj: Any) -> Any:
    """Replace NaN/inf floats by None, recursively (JSON has no NaN)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return obj


class TelemetryWriter:
    """Append-only JSONL writer. Records are formatted by the caller's thread and written and
    flushed line by line by a writer thread, so a slow disk (an SD card on a robot) never stalls
    the control loop; :meth:`close` drains the queue. A killed process loses at most the lines
    still queued (normally none: the writer keeps up within a tick)."""

    def __init__(self, path: str | Path, header: dict[str, Any]):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._f: IO[str] | None = open(self.path, "w", buffering=1, encoding="utf-8")  # noqa: SIM115 (closed in close())
        self._q: queue.SimpleQueue[str | None] = queue.SimpleQueue()
        self._thread = threading.Thread(target=self._drain, name="telemetry-writer", daemon=True)
        self._thread.start()
        self._write({"type": "header", "unix_time": time.time(), **header})

    def _drain(self) -> None:
        assert self._f is not None
        while (line := self._q.get()) is not None:
            self._f.write(line)

    def _write(self, rec: dict[str, Any]) -> None:
        if self._f is not None:
            self._q.put(json.dumps(rec, separators=(",", ":"), allow_nan=False) + "\n")

    def tick(self, i: int, t: float, period: float, late: float, phase: str,
             cmd: Sequence[float], present: Sequence[float] | None) -> None:
        self._write({"type": "tick", "i": i, "t": round(t, 6), "period": round(period, 6), "late": round(late, 6),
                     "phase": phase, "cmd": _r(cmd), "present": _r(present)})

    def event(self, kind: str, message: str, servo: int | None = None, **extra: Any) -> None:
        self._write({"type": "event", "kind": kind, "message": message, "servo": servo, **extra})

    def stop(self, **fields: Any) -> None:
        self._write(_finite({"type": "stop", **fields}))

    def close(self) -> None:
        if self._f is not None:
            self._q.put(None)
            self._thread.join()
            self._f.close()
            self._f = None


@dataclass(frozen=True)
class Telemetry:
    header: dict[str, Any]
    ticks: list[dict[str, Any]]
    events: list[dict[str, Any]]
    stop: dict[str, Any] | None
    truncated: bool  # last line was cut (process died while writing)


def read_telemetry(path: str | Path) -> Telemetry:
    """Read a telemetry file, tolerating a truncated last line."""
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as err:
        raise InputFileError(f"{path}: cannot read telemetry ({err})") from err
    header: dict[str, Any] | None = None
    ticks, events, stop, truncated = [], [], None, False
    for k, line in enumerate(lines):
        try:
            rec = json.loads(line)
        except json.JSONDecodeError:
            if k == len(lines) - 1:
                truncated = True
                break
            raise InputFileError(f"{path}: line {k + 1} is not JSON; the file is damaged") from None
        kind = rec.get("type")
        if kind == "header":
            header = rec
        elif kind == "tick":
            ticks.append(rec)
        elif kind == "event":
            events.append(rec)
        elif kind == "stop":
            stop = rec
    if header is None:
        raise InputFileError(f"{path}: no header line; not a motion2robot telemetry file")
    return Telemetry(header, ticks, events, stop, truncated)

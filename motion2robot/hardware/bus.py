"""The servo bus as the streamer sees it: nothing else touches servos.

Register values are integers as stored (ticks, raw units), signed registers decoded. Every
failure is a typed :class:`~motion2robot.hardware.errors.HardwareError` naming the servo and
the cause; the Alert bit is not an error of the call but is reported in :class:`SyncReading`
status bytes and :class:`ServoInfo`, so the caller decides (the guard does).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from motion2robot.hardware.errors import HardwareError

if TYPE_CHECKING:  # typing.Self is Python 3.11+
    from typing import Self


@dataclass(frozen=True)
class ServoInfo:
    """A servo found on the bus: model number and name, firmware, Hardware Error Status."""

    id: int
    model_number: int
    model: str
    firmware: int
    hardware_error_status: int | None = None


@dataclass(frozen=True)
class SyncReading:
    """Values of one register read from several servos, and each servo's status error byte
    (bit 7 = Alert: read Hardware Error Status)."""

    values: Mapping[int, int]
    status: Mapping[int, int]

    def alerts(self) -> list[int]:
        return [i for i, e in self.status.items() if e & 0x80]


class ServoBus(ABC):
    """Abstract servo bus (Protocol 2.0 semantics). Use as a context manager: closes the port."""

    @abstractmethod
    def open(self) -> None: ...

    @abstractmethod
    def close(self) -> None:
        """Close the port; never raises."""

    @property
    @abstractmethod
    def is_open(self) -> bool:
        """True while the port is usable (False after close or a port failure)."""

    @abstractmethod
    def ping(self, servo_id: int) -> ServoInfo: ...

    @abstractmethod
    def scan(self, ids: Iterable[int] | None = None) -> list[ServoInfo]:
        """Servos answering (broadcast ping when ``ids`` is None), with error status."""

    @abstractmethod
    def read(self, servo_id: int, register: str) -> int: ...

    @abstractmethod
    def write(self, servo_id: int, register: str, value: int) -> None: ...

    @abstractmethod
    def sync_write(self, register: str, values: Mapping[int, int]) -> None:
        """One broadcast packet writing ``values[id]`` to each servo (no reply)."""

    @abstractmethod
    def sync_read(self, register: str, ids: Sequence[int]) -> SyncReading:
        """One register from several servos (fast sync read where supported)."""

    @abstractmethod
    def reboot(self, servo_id: int) -> None: ...

    def recoveries(self) -> list[str]:
        """Messages about failures that a bounded retry recovered from since the last call
        (e.g. a lost reply); the streamer writes them to telemetry. Default: none."""
        return []

    def set_torque(self, ids: Iterable[int], enabled: bool) -> dict[int, HardwareError | None]:
        """Torque on/off servo by servo, going on past failures; ID -> None or the error."""
        out: dict[int, HardwareError | None] = {}
        for i in ids:
            try:
                self.write(i, "torque_enable", 1 if enabled else 0)
                out[i] = None
            except HardwareError as err:
                out[i] = err
        return out

    def __enter__(self) -> Self:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

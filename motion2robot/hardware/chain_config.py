"""Configuration and fault descriptions of the virtual servo chain (plain data, picklable)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from motion2robot.hardware.virtual_servo import OVERLOAD

FAULT_KINDS = ("drop_replies", "corrupt_crc", "alert", "vanish", "close_port", "stall", "watchdog")
_GOAL_ADDR = 116


@dataclass(frozen=True)
class Fault:
    """A fault to inject once ``after_writes`` goal-position writes have been seen.

    kind: "drop_replies" (servo stays silent for ``count`` replies, None = for ever),
    "corrupt_crc" (its next ``count`` status replies carry a wrong CRC), "alert" (Hardware
    Error Status |= ``bits``, default overload; torque cut), "vanish" (servo gone from the
    bus), "close_port" (the chain closes the pty: the port dies under the host), "stall" (the
    servo stops moving, e.g. blocked by an obstacle, yet answers normally with no error bit),
    "watchdog" (its Bus Watchdog trips now, as if it had missed packets)."""

    kind: str
    servo_id: int | None = None
    after_writes: int = 0
    count: int | None = None
    bits: int = OVERLOAD

    def __post_init__(self) -> None:
        if self.kind not in FAULT_KINDS:
            raise ValueError(f"unknown fault {self.kind!r}; use one of {FAULT_KINDS}")
        if self.kind != "close_port" and self.servo_id is None:
            raise ValueError(f"fault {self.kind} needs a servo_id")


@dataclass(frozen=True)
class ChainConfig:
    ids: tuple[int, ...]
    model: str = "XM430-W350"
    baud: int = 1_000_000
    wire_time: bool = False
    return_delay_time: int = 0  # register units of 2 us
    positions: Mapping[int, int] = field(default_factory=dict)  # initial ticks per ID
    firmware: int = 48
    realtime: bool = True  # run the chain under SCHED_FIFO when permitted: like real servos,
    # it should not be delayed by host load

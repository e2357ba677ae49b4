"""Where the servos are: a real port or a virtual chain; shared by the stream and servos CLIs.

``open_bus_factory`` is a context manager yielding a zero-argument factory of
:class:`~motion2robot.hardware.dynamixel_bus.DynamixelBus`; for ``--virtual`` it first starts a
:class:`~motion2robot.hardware.virtual_chain.VirtualChain` with one servo per servo-map entry
(Return Delay Time 0) and stops it afterwards.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass

from motion2robot.cli.numbers import BAUD, LATENCY_MS
from motion2robot.errors import UserError
from motion2robot.hardware.dynamixel_bus import DynamixelBus
from motion2robot.hardware.virtual_chain import PTY_LATENCY_MS, VirtualChain
from motion2robot.robot.servo_map import ServoMap


@dataclass(frozen=True)
class BusTarget:
    """A real ``port`` or ``virtual`` chain at ``baud``; ``latency_ms`` replaces the SDK's 16 ms."""

    port: str | None
    virtual: bool
    baud: int
    latency_ms: float = 1.0
    wire_time: bool = True
    realtime: bool = False

    def describe(self) -> str:
        return f"virtual chain at {self.baud} baud" if self.virtual else f"{self.port} at {self.baud} baud"


def add_bus_options(p: argparse.ArgumentParser, *, required: bool = True) -> None:
    g = p.add_mutually_exclusive_group(required=required)
    g.add_argument("--virtual", action="store_true",
                   help="use a virtual servo chain (Protocol 2.0 on a pseudo-terminal) instead of hardware")
    g.add_argument("--port", metavar="DEV", help="serial device of the servo bus, e.g. /dev/ttyUSB0")
    p.add_argument("--baud", type=BAUD, help="bus baud rate in bit/s (default: the robot config's, e.g. 2000000)")
    p.add_argument("--latency-ms", type=LATENCY_MS,
                   help="USB latency timer the SDK timeouts assume (ms; default 1 for a port, set the adapter to "
                        "match; 10 for the virtual chain's pty)")
    p.add_argument("--no-wire-time", action="store_true", help="virtual chain: do not emulate byte times on the wire")


def target_from_args(args: argparse.Namespace, servo_map: ServoMap | None) -> BusTarget:
    baud = args.baud or (servo_map.baud if servo_map else None)
    if not baud:
        raise UserError("no baud rate: give --baud (the robot config has no [servos] section)")
    latency = args.latency_ms if args.latency_ms is not None else (PTY_LATENCY_MS if args.virtual else 1.0)
    return BusTarget(args.port, bool(args.virtual), int(baud), float(latency), not args.no_wire_time,
                     bool(getattr(args, "realtime", False)))


@contextmanager
def open_bus_factory(target: BusTarget, servo_map: ServoMap, *, positions: Mapping[int, int] | None = None,
                     retries: int = 1) -> Iterator[Callable[[], DynamixelBus]]:
    """Yield a factory of unopened DynamixelBus objects for ``target`` (error messages name joints)."""
    names = {s.id: s.joint for s in servo_map.servos}

    def factory(port: str) -> Callable[[], DynamixelBus]:
        return lambda: DynamixelBus(port, target.baud, servo_map.model, latency_timer_ms=target.latency_ms,
                                    retries=retries, names=names)

    if target.virtual:
        with VirtualChain([s.id for s in servo_map.servos], model=servo_map.model, baud=target.baud,
                          wire_time=target.wire_time, positions=positions) as chain:
            yield factory(chain.port_name)
    else:
        assert target.port
        yield factory(target.port)

"""A chain of virtual Dynamixel servos on the far end of a pseudo-terminal.

A child process owns the pty master and speaks Protocol 2.0 byte for byte (header, stuffing,
CRC-16, status packets with error bits): ping (unicast and broadcast), read, write, sync read,
sync write, fast sync read, reboot. The host opens :attr:`VirtualChain.port_name` with the real
dynamixel-sdk, so the tests exercise the real host code path.

Timing: with ``wire_time=True`` every packet occupies the bus for ``10 bits/byte / baud`` per
byte (a packet's bytes arrive in the pty at once; the chain waits for the wire time before it
acts and before it delivers each reply), replies follow each servo's Return Delay Time. Fault
injection (:class:`Fault`) is scheduled on the number of goal-position writes seen on the wire,
so tests are deterministic in ticks. The chain also records every goal position it receives
(:meth:`VirtualChain.wire_log`) and byte counts (:meth:`VirtualChain.stats`).
"""

from __future__ import annotations

import gc
import multiprocessing
import os
import signal
import tty
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any

from motion2robot.hardware.chain_config import ChainConfig, Fault
from motion2robot.hardware.chain_server import ChainServer
from motion2robot.hardware.timing import realtime_priority

if TYPE_CHECKING:  # typing.Self is Python 3.11+
    from typing import Self

#: Latency (ms) a host should assume for the pty relay, in place of a USB adapter's latency timer.
#: The kernel moves pty bytes in a worker thread; on a loaded 2-core machine a 1-byte round trip
#: measured p50 0.03 ms, p99.9 1.3 ms, max 4.1 ms (SCHED_FIFO ends, load average 4.5); a shared CI
#: virtual machine also stalls both processes for ~10 ms now and then (a 20 ms tick was seen), which
#: a 4 ms assumption turned into two timed-out reads in a row, i.e. a comm fault of a healthy chain.
PTY_LATENCY_MS = 10.0

__all__ = ["PTY_LATENCY_MS", "ChainConfig", "Fault", "VirtualChain"]


def _child_main(cfg: ChainConfig, master: int, slave: int, conn: Any) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the host's business
    os.close(slave)
    gc.disable()  # no reference cycles are made here; a collection would stall the replies
    with realtime_priority(cfg.realtime, 60):
        chain = ChainServer(cfg, master)
        conn.send("ready")
        chain.serve(conn)


class VirtualChain:
    """N virtual servos behind a pseudo-terminal; use as a context manager.

    ``ids``: servo IDs; ``baud``: emulated bus rate (bit/s); ``wire_time``: emulate the time
    bytes take on the wire; ``return_delay_time``: register value (2 us units) of every servo;
    ``positions``: initial present position (ticks) per ID (default 2048); ``realtime``: run
    the chain process under SCHED_FIFO when the OS allows it (default: servos do not share the
    host's CPU, so the emulation should not either)."""

    def __init__(self, ids: Iterable[int], *, model: str = "XM430-W350", baud: int = 1_000_000,
                 wire_time: bool = False, return_delay_time: int = 0,
                 positions: Mapping[int, int] | None = None, firmware: int = 48, realtime: bool = True):
        self.config = ChainConfig(tuple(int(i) for i in ids), model, int(baud), bool(wire_time),
                                  int(return_delay_time), dict(positions or {}), firmware, realtime)
        self._proc: Any = None
        self._conn: Any = None
        self._slave: int | None = None
        self.port_name = ""

    def start(self) -> VirtualChain:
        master, slave = os.openpty()
        tty.setraw(slave)
        ctx = multiprocessing.get_context("fork")
        parent_conn, child_conn = ctx.Pipe()
        self._proc = ctx.Process(target=_child_main, args=(self.config, master, slave, child_conn),
                                 daemon=True, name="virtual-dynamixel-chain")
        self._proc.start()
        os.close(master)
        child_conn.close()
        self._conn, self._slave = parent_conn, slave
        self.port_name = os.ttyname(slave)
        if not parent_conn.poll(10.0) or parent_conn.recv() != "ready":
            self.stop()
            raise RuntimeError("virtual chain did not start within 10 s")
        return self

    def _ask(self, *msg: Any) -> Any:
        if self._conn is None:
            raise RuntimeError("virtual chain is not running")
        self._conn.send(msg)
        if not self._conn.poll(10.0):
            raise RuntimeError("virtual chain did not answer within 10 s")
        out = self._conn.recv()
        if isinstance(out, Exception):
            raise out
        return out

    def inject(self, fault: Fault) -> None:
        """Schedule ``fault`` (see :class:`Fault`)."""
        self._ask("inject", fault)

    def snapshot(self) -> dict[int, dict[str, Any]]:
        """Per servo: alive, torque, goal, present, hardware_error_status, bus_watchdog."""
        return self._ask("snapshot")

    def wire_log(self) -> list[tuple[float, int, int]]:
        """Every goal position received: (time s, servo ID, ticks), in wire order."""
        return self._ask("wire_log")

    def stats(self) -> dict[str, Any]:
        """rx_bytes (host to servos), tx_bytes, packets per instruction, goal_writes, port_open,
        bus_time_s (modelled bus occupation: bytes on the wire and Return Delay Times)."""
        return self._ask("stats")

    def set_register(self, servo_id: int, name: str, value: int) -> None:
        """Test hook: poke a register of one servo directly (not over the bus)."""
        self._ask("set", servo_id, name, value)

    def stop(self) -> None:
        if self._proc is not None:
            try:
                if self._proc.is_alive():
                    self._ask("stop")
            except (RuntimeError, OSError, EOFError):
                pass
            self._proc.join(2.0)
            if self._proc.is_alive():
                self._proc.terminate()
                self._proc.join(2.0)
            self._proc = None
        if self._conn is not None:
            self._conn.close()
            self._conn = None
        if self._slave is not None:
            os.close(self._slave)
            self._slave = None

    def __enter__(self) -> Self:
        return self.start() if self._proc is None else self

    def __exit__(self, *exc: object) -> None:
        self.stop()

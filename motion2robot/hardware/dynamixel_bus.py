"""ServoBus on the official dynamixel-sdk (PortHandler, PacketHandler 2.0, GroupSyncWrite,
GroupSyncRead with Fast Sync Read).

Latency: the SDK computes every reply timeout as ``bytes * byte_time + 2 * LATENCY_TIMER + 2``
ms with the module constant ``LATENCY_TIMER = 16``, so a missing reply costs >= 34 ms.
:class:`LowLatencyPortHandler` replaces that constant with ``latency_timer_ms`` (default 1 ms,
matching a USB adapter whose latency timer is set to 1 ms, see docs/hardware.md) and reads
with a short blocking timeout instead of the SDK's busy spin. :func:`usb_latency_timer` reads
the adapter's setting from sysfs so callers can warn when it is still 16 ms.

Every call returns data or raises a typed error naming the servo and quoting the SDK's
result/error text; communication failures are retried ``retries`` times (bounded).
"""

from __future__ import annotations

import os
import termios
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import serial
from dynamixel_sdk import (
    COMM_SUCCESS,
    GroupSyncRead,
    GroupSyncWrite,
    PacketHandler,
    PortHandler,
)

from motion2robot.hardware.bus import ServoBus, ServoInfo, SyncReading
from motion2robot.hardware.control_table import ControlTable, control_table, model_name
from motion2robot.hardware.errors import CommError, PortError, ServoStatusError
from motion2robot.hardware.protocol import error_text

_PORT_EXC = (serial.SerialException, OSError, termios.error)


class LowLatencyPortHandler(PortHandler):
    """PortHandler whose packet timeout uses ``latency_timer_ms`` instead of the SDK's 16 ms
    constant, and whose reads block up to ``read_block_ms`` instead of spinning."""

    def __init__(self, port_name: str, latency_timer_ms: float = 1.0, read_block_ms: float = 1.0):
        super().__init__(port_name)
        self.latency_timer_ms = float(latency_timer_ms)
        self.read_block_s = read_block_ms / 1000.0

    def setPacketTimeout(self, packet_length: int) -> None:
        self.packet_start_time = self.getCurrentTime()
        self.packet_timeout = self.tx_time_per_byte * packet_length + 2.0 * self.latency_timer_ms + 2.0

    def setupPort(self, cflag_baud: int) -> bool:
        ok = super().setupPort(cflag_baud)
        self.ser.timeout = self.read_block_s
        try:
            self.ser.set_low_latency_mode(True)  # ASYNC_LOW_LATENCY on real serial drivers
        except (AttributeError, ValueError, OSError, NotImplementedError):
            pass  # pty or driver without it
        return ok


def usb_latency_timer(port: str) -> int | None:
    """The FTDI latency timer (ms) of ``/dev/ttyUSBn`` from sysfs, None if not applicable."""
    name = Path(os.path.realpath(port)).name
    p = Path("/sys/bus/usb-serial/devices") / name / "latency_timer"
    try:
        return int(p.read_text().strip())
    except (OSError, ValueError):
        return None


class DynamixelBus(ServoBus):
    """Protocol 2.0 bus on ``port`` at ``baud`` for servos of ``model``.

    ``names`` (ID -> joint) makes error messages name the joint; ``fast_sync_read``: True,
    False, or None = use it when every servo read reports a firmware that supports it."""

    def __init__(self, port: str, baud: int, model: str = "XM430-W350", *, latency_timer_ms: float = 1.0,
                 retries: int = 1, fast_sync_read: bool | None = None, names: Mapping[int, str] | None = None):
        self.port_name = port
        self.baud = int(baud)
        self.table: ControlTable = control_table(model)
        self.latency_timer_ms = latency_timer_ms
        self.retries = max(0, int(retries))
        self.fast_sync_read = fast_sync_read
        self.names = dict(names or {})
        self._port: LowLatencyPortHandler | None = None
        self._ph = PacketHandler(2.0)
        self._writers: dict[str, GroupSyncWrite] = {}
        self._readers: dict[tuple[str, tuple[int, ...]], GroupSyncRead] = {}
        self._firmware: dict[int, int] = {}
        self._recovered: list[str] = []

    def recoveries(self) -> list[str]:
        out, self._recovered = self._recovered, []
        return out

    # -- plumbing -------------------------------------------------------------------------
    def who(self, servo_id: int | None) -> str:
        if servo_id is None:
            return f"bus {self.port_name}"
        n = self.names.get(servo_id)
        return f"servo {servo_id} ({n})" if n else f"servo {servo_id}"

    def open(self) -> None:
        port = LowLatencyPortHandler(self.port_name, self.latency_timer_ms)
        try:
            ok = port.openPort() and port.setBaudRate(self.baud)
        except _PORT_EXC as err:
            raise PortError(f"cannot open {self.port_name} ({err}); check the device path, that no other "
                            "program uses it and that you are in the 'dialout' group") from err
        if not ok:
            raise PortError(f"cannot set {self.port_name} to {self.baud} baud; use one of 57600, 115200, "
                            "1000000, 2000000, 3000000, 4000000")
        self._port = port

    def close(self) -> None:
        port, self._port = self._port, None
        if port is not None and port.ser is not None:
            try:
                port.closePort()
            except _PORT_EXC:
                pass

    @property
    def is_open(self) -> bool:
        return self._port is not None

    def _p(self) -> LowLatencyPortHandler:
        if self._port is None:
            raise PortError(f"{self.port_name} is not open (or was closed after a port failure); reopen it")
        return self._port

    def _sdk(self, what: str, servo_id: int | None, fn: Callable[..., Any], *args: Any) -> Any:
        """Call the SDK; a dead port becomes PortError and the port is closed."""
        port = self._p()
        try:
            return fn(*args)
        except _PORT_EXC as err:
            port.is_using = False
            self.close()
            raise PortError(f"{self.port_name} failed while {what} for {self.who(servo_id)} ({err}); "
                            "check the USB cable and adapter, then restart", servo_id) from err

    def _comm_error(self, what: str, servo_id: int | None, result: int, tries: int) -> CommError:
        text = self._ph.getTxRxResult(result)
        return CommError(f"{self.who(servo_id)}: {what} failed after {tries} tries: {text}; "
                         "check its cable, power and ID", servo_id)

    def _status_error(self, what: str, servo_id: int, error: int) -> ServoStatusError:
        return ServoStatusError(f"{self.who(servo_id)}: {what} refused with {error_text(error)} "
                                f"({self._ph.getRxPacketError(error & 0x7F)})", servo_id)

    def _retry(self, what: str, servo_id: int, fn: Callable[..., Any], *args: Any) -> tuple[Any, int]:
        """Run a unicast SDK call until COMM_SUCCESS; returns (data, status error byte)."""
        for attempt in range(self.retries + 1):
            out = self._sdk(what, servo_id, fn, self._p(), *args)
            if len(out) == 3:
                data, result, error = out
            else:
                (result, error), data = out, None
            if result == COMM_SUCCESS:
                if error & 0x7F:
                    raise self._status_error(what, servo_id, error)
                if attempt:
                    self._recovered.append(f"{self.who(servo_id)}: {what} needed {attempt + 1} tries")
                return data, error
        raise self._comm_error(what, servo_id, result, self.retries + 1)

    # -- ServoBus -------------------------------------------------------------------------
    def ping(self, servo_id: int) -> ServoInfo:
        number, error = self._retry("ping", servo_id, self._ph.ping, servo_id)
        fw = self.read(servo_id, "firmware_version")
        self._firmware[servo_id] = fw
        return ServoInfo(servo_id, number, model_name(number), fw, self._hes_if_alert(servo_id, error))

    def _hes_if_alert(self, servo_id: int, error: int) -> int:
        return self.read(servo_id, "hardware_error_status") if error & 0x80 else 0

    def scan(self, ids: Iterable[int] | None = None) -> list[ServoInfo]:
        if ids is None:
            found, result = self._sdk("broadcast ping", None, self._ph.broadcastPing, self._p())
            if result != COMM_SUCCESS and not found:
                return []
            ids = sorted(found)
        out = []
        for i in ids:
            try:
                info = self.ping(i)
            except CommError:
                continue
            out.append(ServoInfo(info.id, info.model_number, info.model, info.firmware,
                                 self.read(i, "hardware_error_status")))
        return out

    def read(self, servo_id: int, register: str) -> int:
        r = self.table[register]
        data, _ = self._retry(f"reading {r.name}", servo_id, self._ph.readTxRx, servo_id, r.address, r.size)
        if len(data) != r.size:
            raise CommError(f"{self.who(servo_id)}: reading {r.name} returned {len(data)} bytes instead of {r.size}", servo_id)
        return r.decode(bytes(data))

    def write(self, servo_id: int, register: str, value: int) -> None:
        r = self.table[register]
        if not r.writable:
            raise ServoStatusError(f"{self.who(servo_id)}: {r.name} is read-only", servo_id)
        self._retry(f"writing {r.name}={value}", servo_id, self._ph.writeTxRx, servo_id, r.address, r.size, list(r.encode(value)))

    def reboot(self, servo_id: int) -> None:
        self._retry("reboot", servo_id, self._ph.reboot, servo_id)

    def sync_write(self, register: str, values: Mapping[int, int]) -> None:
        r = self.table[register]
        g = self._writers.get(register)
        if g is None or g.port is not self._port:
            g = self._writers[register] = GroupSyncWrite(self._p(), self._ph, r.address, r.size)
        g.clearParam()
        for i, v in values.items():
            g.addParam(int(i), list(r.encode(v)))
        result = self._sdk(f"sync-writing {r.name}", None, g.txPacket)
        if result != COMM_SUCCESS:
            raise CommError(f"{self.who(None)}: sync write of {r.name} failed: {self._ph.getTxRxResult(result)}")

    def uses_fast_sync_read(self, ids: Sequence[int]) -> bool:
        if self.fast_sync_read is not None:
            return self.fast_sync_read
        if any(i not in self._firmware for i in ids):
            return False
        return min(self._firmware[i] for i in ids) >= self.table.fast_sync_read_firmware

    def sync_read(self, register: str, ids: Sequence[int]) -> SyncReading:
        """Fast sync read when supported (one reply packet); if it fails, a plain sync read
        (one status packet per servo) names the servo at fault; bounded by ``retries``."""
        r = self.table[register]
        key = (register, tuple(ids))
        g = self._readers.get(key)
        if g is None or g.port is not self._port:
            g = self._readers[key] = GroupSyncRead(self._p(), self._ph, r.address, r.size)
            for i in ids:
                g.addParam(int(i))
        attempts, failed = self.retries + 1, 0
        if self.uses_fast_sync_read(ids):
            got = self._fast_read(g, r, ids)
            if got is not None:
                return got
            attempts, failed = attempts - 1, 1
        err: CommError | None = None
        for _ in range(max(1, attempts)):
            try:
                got = self._plain_read(g, r, ids, self.retries + 1)
            except CommError as e:
                err, failed = e, failed + 1
                continue
            if failed:
                self._recovered.append(f"{self.who(None)}: sync read of {r.name} succeeded after {failed} failed "
                                       "attempt(s) (fast sync read first, then plain sync read)")
            return got
        raise err  # type: ignore[misc]

    def _fast_read(self, g: GroupSyncRead, r: Any, ids: Sequence[int]) -> SyncReading | None:
        result = self._sdk(f"fast-sync-reading {r.name}", None, g.fastSyncReadTxPacket)
        if result != COMM_SUCCESS:
            return None
        n = len(ids) * (r.size + 4)
        raw, result, _ = self._sdk(f"fast-sync-reading {r.name}", None, self._ph.fastSyncReadRx, self._p(), 0xFE, n)
        if result != COMM_SUCCESS or len(raw) != n:
            return None
        values, status = {}, {}
        for k, i in enumerate(ids):
            sec = raw[k * (r.size + 4):(k + 1) * (r.size + 4)]
            if sec[1] != i:
                return None
            if sec[0] & 0x7F:
                raise self._status_error(f"fast sync read of {r.name}", i, sec[0])
            status[i] = sec[0]
            values[i] = r.decode(bytes(sec[2:2 + r.size]))
        return SyncReading(values, status)

    def _plain_read(self, g: GroupSyncRead, r: Any, ids: Sequence[int], tries: int) -> SyncReading:
        result = self._sdk(f"sync-reading {r.name}", None, g.txPacket)
        if result != COMM_SUCCESS:
            raise CommError(f"{self.who(None)}: sync read of {r.name} not sent: {self._ph.getTxRxResult(result)}")
        values, status = {}, {}
        for i in ids:
            data, result, error = self._sdk(f"sync-reading {r.name}", i, self._ph.readRx, self._p(), i, r.size)
            if result != COMM_SUCCESS or len(data) != r.size:
                raise self._comm_error(f"sync read of {r.name}", i, result, tries)
            if error & 0x7F:
                raise self._status_error(f"sync read of {r.name}", i, error)
            values[i], status[i] = r.decode(bytes(data)), error
        return SyncReading(values, status)


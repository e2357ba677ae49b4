"""Dynamixel Protocol 2.0 framing: CRC-16, byte stuffing, packet encoding and a stream parser.

Instruction: ``FF FF FD 00 | ID | LEN_L LEN_H | INST | params | CRC_L CRC_H`` with
LEN = len(stuffed INST + params) + 2. Status packets use INST 0x55 followed by the error byte.
Used by the virtual servo chain (servo side) and for byte counts; the host side of
:class:`~motion2robot.hardware.dynamixel_bus.DynamixelBus` is the official dynamixel-sdk.
"""

from __future__ import annotations

from dataclasses import dataclass

HEADER = b"\xff\xff\xfd\x00"
BROADCAST_ID = 0xFE
MAX_ID = 252

PING, READ, WRITE, REG_WRITE, ACTION, FACTORY_RESET, REBOOT, CLEAR = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x08, 0x10
STATUS = 0x55
SYNC_READ, SYNC_WRITE, FAST_SYNC_READ = 0x82, 0x83, 0x8A
BULK_READ, BULK_WRITE, FAST_BULK_READ = 0x92, 0x93, 0x9A

ERR_RESULT_FAIL, ERR_INSTRUCTION, ERR_CRC, ERR_DATA_RANGE, ERR_DATA_LENGTH, ERR_DATA_LIMIT, ERR_ACCESS = 1, 2, 3, 4, 5, 6, 7
ERR_ALERT = 0x80
ERROR_NAMES = {
    ERR_RESULT_FAIL: "result fail", ERR_INSTRUCTION: "instruction error", ERR_CRC: "CRC error",
    ERR_DATA_RANGE: "data range error", ERR_DATA_LENGTH: "data length error",
    ERR_DATA_LIMIT: "data limit error", ERR_ACCESS: "access error",
}


def _crc_table() -> tuple[int, ...]:
    table = []
    for i in range(256):
        c = i << 8
        for _ in range(8):
            c = ((c << 1) ^ 0x8005) if c & 0x8000 else (c << 1)
        table.append(c & 0xFFFF)
    return tuple(table)


_CRC_TABLE = _crc_table()


def crc16(data: bytes | bytearray, crc: int = 0) -> int:
    """CRC-16 of Protocol 2.0 (polynomial 0x8005, initial 0), continuing from ``crc``."""
    table = _CRC_TABLE
    for b in data:
        crc = ((crc << 8) ^ table[((crc >> 8) ^ b) & 0xFF]) & 0xFFFF
    return crc


def stuff(payload: bytes) -> bytes:
    """Insert 0xFD after every ``FF FF FD`` in INST+params (done before LEN and CRC)."""
    if b"\xff\xff\xfd" not in payload:
        return bytes(payload)
    out = bytearray()
    for b in payload:
        out.append(b)
        if b == 0xFD and len(out) >= 3 and out[-3] == 0xFF and out[-2] == 0xFF:
            out.append(0xFD)
    return bytes(out)


def unstuff(payload: bytes) -> bytes:
    """Remove the stuffing byte of every ``FF FF FD FD`` sequence."""
    if b"\xff\xff\xfd\xfd" not in payload:
        return bytes(payload)
    out = bytearray()
    i = 0
    while i < len(payload):
        out.append(payload[i])
        if payload[i] == 0xFD and len(out) >= 3 and out[-3] == 0xFF and out[-2] == 0xFF \
                and i + 1 < len(payload) and payload[i + 1] == 0xFD:
            i += 1
        i += 1
    return bytes(out)


def packet(servo_id: int, instruction: int, params: bytes = b"") -> bytes:
    """A complete packet (header, ID, LEN, stuffed INST+params, CRC)."""
    body = stuff(bytes([instruction]) + bytes(params))
    n = len(body) + 2
    head = HEADER + bytes([servo_id, n & 0xFF, n >> 8])
    crc = crc16(head + body)
    return head + body + bytes([crc & 0xFF, crc >> 8])


def status_packet(servo_id: int, error: int, params: bytes = b"") -> bytes:
    """A status packet (INST 0x55, then the error byte, then the parameters)."""
    return packet(servo_id, STATUS, bytes([error]) + bytes(params))


@dataclass(frozen=True)
class Packet:
    """A received packet: ID, instruction, unstuffed params; ``size`` bytes on the wire,
    first byte seen at ``t_start`` (seconds, monotonic clock); ``crc_ok`` False if corrupt."""

    id: int
    instruction: int
    params: bytes
    size: int
    t_start: float
    crc_ok: bool = True


class PacketReader:
    """Incremental parser: ``feed(data, t)`` returns the complete packets found so far.

    Resynchronises on the header after garbage; packets with a bad CRC are returned with
    ``crc_ok=False`` (a servo ignores them)."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self._t_first: float | None = None

    def feed(self, data: bytes, t: float) -> list[Packet]:
        if data:
            if not self._buf:
                self._t_first = t
            self._buf += data
        out: list[Packet] = []
        while True:
            start = self._buf.find(HEADER)
            if start < 0:
                keep = 3 if self._buf.endswith(b"\xff\xff\xfd") else (2 if self._buf.endswith(b"\xff\xff") else (1 if self._buf.endswith(b"\xff") else 0))
                del self._buf[: len(self._buf) - keep]
                break
            if start:
                del self._buf[:start]
            if len(self._buf) < 7:
                break
            n = self._buf[5] | (self._buf[6] << 8)
            total = 7 + n
            if n < 3 or n > 4096:
                del self._buf[:1]
                continue
            if len(self._buf) < total:
                break
            raw = bytes(self._buf[:total])
            del self._buf[:total]
            crc_ok = crc16(raw[:-2]) == (raw[-2] | (raw[-1] << 8))
            body = unstuff(raw[7:-2])
            t0 = t if self._t_first is None else self._t_first
            out.append(Packet(raw[4], body[0], body[1:], total, t0, crc_ok))
            self._t_first = t
        if not self._buf:
            self._t_first = None
        return out


def error_text(error: int) -> str:
    """Human text of a status error byte (without the Alert bit), '' when none."""
    code = error & 0x7F
    return ERROR_NAMES.get(code, f"error code {code}") if code else ""

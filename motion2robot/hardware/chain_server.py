"""The servo side of the virtual chain: Protocol 2.0 dispatch, wire timing, fault injection."""

from __future__ import annotations

import os
import select
import time
from array import array
from typing import Any

from motion2robot.hardware import protocol as P
from motion2robot.hardware.chain_config import ChainConfig, Fault
from motion2robot.hardware.control_table import control_table
from motion2robot.hardware.virtual_servo import VirtualServo

_GOAL_ADDR = 116


class ChainServer:
    """Servo side of the bus: parses instructions from the pty master, drives the virtual servos,
    writes status packets with wire-time emulation; runs in the chain's child process."""

    def __init__(self, cfg: ChainConfig, master: int):
        t = time.monotonic()
        table = control_table(cfg.model)
        self.cfg = cfg
        self.master: int | None = master
        self.servos = {i: VirtualServo(i, table, cfg.positions.get(i, 2048), cfg.return_delay_time, cfg.firmware, t)
                       for i in cfg.ids}
        self.byte_s = 10.0 / cfg.baud if cfg.wire_time else 0.0
        self.bus_free = 0.0
        self.reader = P.PacketReader()
        self.pending: list[Fault] = []
        self.drop: dict[int, float] = {}
        self.corrupt: dict[int, float] = {}
        self.goal_writes = 0
        self.wire = (array("d"), array("B"), array("l"))  # time, ID, goal ticks (no GC-tracked objects)
        self.stats: dict[str, Any] = {"rx_bytes": 0, "tx_bytes": 0, "packets": {}, "bad_crc": 0,
                                      "bus_time_s": 0.0}  # modelled bus occupation: wire time + return delays

    # -- faults ---------------------------------------------------------------------------
    def _activate_faults(self) -> None:
        for f in [f for f in self.pending if self.goal_writes >= f.after_writes]:
            self.pending.remove(f)
            n = float("inf") if f.count is None else f.count
            s = self.servos.get(f.servo_id) if f.servo_id is not None else None
            if f.kind == "drop_replies":
                self.drop[f.servo_id] = n
            elif f.kind == "corrupt_crc":
                self.corrupt[f.servo_id] = n
            elif f.kind == "alert" and s:
                s.hardware_fault(f.bits)
            elif f.kind == "vanish" and s:
                s.alive = False
            elif f.kind == "stall" and s:
                s.stalled = True
            elif f.kind == "watchdog" and s:
                s.trip_watchdog()
            elif f.kind == "close_port" and self.master is not None:
                os.close(self.master)
                self.master = None

    def _consume(self, table: dict[int, float], sid: int) -> bool:
        left = table.get(sid, 0)
        if left <= 0:
            return False
        table[sid] = left - 1
        return True

    # -- wire -----------------------------------------------------------------------------
    def _send_at(self, due: float, data: bytes) -> None:
        delay = due - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        if self.master is not None:
            try:
                os.write(self.master, data)
                self.stats["tx_bytes"] += len(data)
            except OSError:
                pass

    def _reply(self, t: float, replies: list[tuple[VirtualServo, bytes]]) -> float:
        for servo, data in replies:
            if self._consume(self.drop, servo.id):
                continue
            if self._consume(self.corrupt, servo.id):
                data = data[:-1] + bytes([data[-1] ^ 0xFF])
            t += servo.return_delay_s + len(data) * self.byte_s
            self._send_at(t, data)
        return t

    def _fast_reply(self, t: float, servos: list[VirtualServo], addr: int, n: int) -> float:
        """One packet ID 0xFE: 0x55 then per servo [ERR, ID, data, CRC]; each CRC is the running
        CRC of the packet so far, the last one is the packet CRC."""
        length = 1 + len(servos) * (n + 4)
        out = bytearray(P.HEADER + bytes([P.BROADCAST_ID, length & 0xFF, length >> 8, P.STATUS]))
        crc = P.crc16(out)  # ``out`` is what the wire delivers (a corrupted CRC does not change ``crc``)
        for s in servos:
            t += s.return_delay_s
            if not s.alive or self._consume(self.drop, s.id):
                continue
            err, data = s.read(addr, n, t)
            section = bytes([err, s.id]) + data
            out += section
            crc = P.crc16(section, crc)
            clean_crc = bytes([crc & 0xFF, crc >> 8])
            crc = P.crc16(clean_crc, crc)  # running CRC over what the servos sent
            out += bytes([clean_crc[0] ^ (0xFF if self._consume(self.corrupt, s.id) else 0), clean_crc[1]])
        t += len(out) * self.byte_s
        self._send_at(t, bytes(out))
        return t

    def handle(self, pkt: P.Packet) -> None:
        self.stats["rx_bytes"] += pkt.size
        name = f"0x{pkt.instruction:02X}"
        self.stats["packets"][name] = self.stats["packets"].get(name, 0) + 1
        start = max(pkt.t_start, self.bus_free)
        end = start + pkt.size * self.byte_s
        self.bus_free = end
        if not pkt.crc_ok:
            self.stats["bad_crc"] += 1
            self.stats["bus_time_s"] += end - start
            return
        delay = end - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        self.bus_free = self._dispatch(pkt, end)
        self.stats["bus_time_s"] += self.bus_free - start
        self._activate_faults()

    def _alive(self, sid: int) -> VirtualServo | None:
        s = self.servos.get(sid)
        return s if s is not None and s.alive else None

    def _dispatch(self, pkt: P.Packet, t: float) -> float:
        inst, p = pkt.instruction, pkt.params
        if inst in (P.SYNC_WRITE, P.SYNC_READ, P.FAST_SYNC_READ):
            if len(p) < 4:
                return t
            addr, n = p[0] | p[1] << 8, p[2] | p[3] << 8
            if inst == P.SYNC_WRITE:
                return self._sync_write(p[4:], addr, n, t)
            servos = [s for s in (self.servos.get(i) for i in p[4:]) if s is not None]
            for s in servos:
                if s.alive:
                    s.heard(t)
            if inst == P.FAST_SYNC_READ:
                return self._fast_reply(t, servos, addr, n)
            replies = []
            for s in servos:
                if s.alive:
                    err, data = s.read(addr, n, t)
                    replies.append((s, P.status_packet(s.id, err, data)))
            return self._reply(t, replies)
        if pkt.id == P.BROADCAST_ID:
            if inst == P.PING:
                ordered = [s for _, s in sorted(self.servos.items()) if s.alive]
                for s in ordered:
                    s.heard(t)
                return self._reply(t, [(s, P.status_packet(s.id, s.status_error(), self._ping_data(s))) for s in ordered])
            if inst == P.WRITE and len(p) >= 3:
                for s in self.servos.values():
                    if s.alive:
                        s.heard(t)
                        s.write(p[0] | p[1] << 8, p[2:], t)
                self._log_goal(p[0] | p[1] << 8, len(p) - 2, [(i, p[2:]) for i, s in self.servos.items() if s.alive], t)
            return t
        s = self._alive(pkt.id)
        if s is None:
            return t
        s.heard(t)
        srl = s.get("status_return_level")
        if inst == P.PING:
            return self._reply(t, [(s, P.status_packet(s.id, s.status_error(), self._ping_data(s)))])
        if inst == P.READ:
            if len(p) != 4:
                err, data = P.ERR_DATA_LENGTH | s.status_error(), b""
            else:
                err, data = s.read(p[0] | p[1] << 8, p[2] | p[3] << 8, t)
            return self._reply(t, [(s, P.status_packet(s.id, err, data))]) if srl >= 1 else t
        if inst == P.WRITE:
            if len(p) < 3:
                err = P.ERR_DATA_LENGTH | s.status_error()
            else:
                err = s.write(p[0] | p[1] << 8, p[2:], t)
                self._log_goal(p[0] | p[1] << 8, len(p) - 2, [(s.id, p[2:])], t)
            return self._reply(t, [(s, P.status_packet(s.id, err))]) if srl >= 2 else t
        if inst == P.REBOOT:
            t = self._reply(t, [(s, P.status_packet(s.id, s.status_error()))]) if srl >= 2 else t
            s.reboot(t)
            return t
        return self._reply(t, [(s, P.status_packet(s.id, P.ERR_INSTRUCTION | s.status_error()))])

    def _ping_data(self, s: VirtualServo) -> bytes:
        return s.table["model_number"].encode(s.table.model_number) + bytes([s.firmware])

    def _sync_write(self, body: bytes, addr: int, n: int, t: float) -> float:
        blocks = [(body[k], body[k + 1:k + 1 + n]) for k in range(0, len(body) - n, n + 1)]
        for sid, data in blocks:
            s = self._alive(sid)
            if s is not None:
                s.heard(t)
                s.write(addr, data, t)  # no status packet for a broadcast: errors stay silent
        self._log_goal(addr, n, blocks, t)  # every goal seen on the wire, accepted or not
        return t

    def _log_goal(self, addr: int, n: int, blocks: list[tuple[int, bytes]], t: float) -> None:
        if not (addr <= _GOAL_ADDR and _GOAL_ADDR + 4 <= addr + n):
            return
        off = _GOAL_ADDR - addr
        for sid, data in blocks:
            self.wire[0].append(t)
            self.wire[1].append(sid)
            self.wire[2].append(int.from_bytes(data[off:off + 4], "little", signed=True))
        self.goal_writes += 1

    # -- control --------------------------------------------------------------------------
    def command(self, msg: tuple) -> Any:
        op = msg[0]
        if op == "inject":
            self.pending.append(msg[1])
            self._activate_faults()
            return True
        if op == "snapshot":
            now = time.monotonic()
            out = {}
            for i, s in self.servos.items():
                s.advance(now)
                out[i] = {"alive": s.alive, "torque": s.torque, "goal": s.get("goal_position"),
                          "present": s.get("present_position"), "hardware_error_status": s.get("hardware_error_status"),
                          "bus_watchdog": s.mem[98], "return_delay_time": s.mem[9]}
            return out
        if op == "wire_log":
            return list(zip(*self.wire))
        if op == "stats":
            return {**self.stats, "goal_writes": self.goal_writes, "port_open": self.master is not None}
        if op == "set":
            _, sid, name, value = msg
            self.servos[sid]._set(name, value)
            if name == "present_position":
                self.servos[sid].pos = float(value)
            return True
        raise ValueError(f"unknown command {op!r}")

    def serve(self, conn: Any) -> None:
        parent = os.getppid()
        while True:
            fds = [conn] + ([self.master] if self.master is not None else [])
            ready, _, _ = select.select(fds, [], [], 0.005)
            now = time.monotonic()
            if self.master is not None and self.master in ready:
                try:
                    data = os.read(self.master, 65536)
                except OSError:  # no slave open at the moment
                    data = b""
                    time.sleep(0.001)
                for pkt in self.reader.feed(data, now):
                    self.handle(pkt)
            if conn in ready:
                try:
                    msg = conn.recv()
                except EOFError:
                    return
                if msg[0] == "stop":
                    conn.send(True)
                    return
                try:
                    conn.send(self.command(msg))
                except Exception as err:  # noqa: BLE001 - report to the parent instead of dying silently
                    conn.send(err)
            for s in self.servos.values():
                s.advance(now)
            if os.getppid() != parent:
                return

"""One virtual Dynamixel servo: a control table in memory with the EEPROM/RAM rules, a position
that moves towards the goal within the servo's speed, the Bus Watchdog and hardware errors.

Pure state machine driven by the chain (:mod:`virtual_chain`) with explicit times in seconds
(monotonic clock); it never touches the wire.
"""

from __future__ import annotations

import math

from motion2robot.hardware import protocol as P
from motion2robot.hardware.control_table import ControlTable

OVERLOAD = 1 << 5


class VirtualServo:
    """Servo ``servo_id`` of model ``table`` at ``position`` ticks; ``firmware`` version."""

    def __init__(self, servo_id: int, table: ControlTable, position: int = 2048,
                 return_delay_time: int = 0, firmware: int = 48, t: float = 0.0):
        self.table = table
        self.firmware = firmware
        self.mem = bytearray(table.size)
        self._reset_memory()
        self._set("id", servo_id)
        self._set("return_delay_time", return_delay_time)
        self.pos = float(position)
        self._set("goal_position", int(position))
        self.t = t
        self.bus_seen = t
        self.alive = True  # False: vanished from the bus (no reply, ignores everything)
        self.stalled = False  # True: blocked, the position no longer moves (no error reported)

    # -- memory -------------------------------------------------------------------------
    def _reset_memory(self, keep_eeprom: bool = False) -> None:
        for r in self.table.registers.values():
            if keep_eeprom and r.address < self.table.eeprom_end:
                continue
            self.mem[r.address:r.address + r.size] = r.encode(r.default)
        self.mem[6] = self.firmware

    def _set(self, name: str, value: int) -> None:
        r = self.table[name]
        self.mem[r.address:r.address + r.size] = r.encode(value)

    def get(self, name: str) -> int:
        r = self.table[name]
        return r.decode(bytes(self.mem[r.address:r.address + r.size]))

    @property
    def id(self) -> int:
        return self.mem[7]

    @property
    def torque(self) -> bool:
        return bool(self.mem[64])

    def status_error(self) -> int:
        """Error byte of the next status packet: Alert while Hardware Error Status is non-zero."""
        return P.ERR_ALERT if self.get("hardware_error_status") else 0

    @property
    def return_delay_s(self) -> float:
        return self.mem[9] * 2e-6

    # -- behaviour ----------------------------------------------------------------------
    def speed_ticks_per_s(self) -> float:
        rpm_units = self.get("velocity_limit")
        profile = self.get("profile_velocity")
        if profile:
            rpm_units = min(rpm_units, profile) if rpm_units else profile
        return rpm_units * self.table.velocity_unit_rpm / 60.0 * self.table.ticks_per_rev

    def advance(self, t: float) -> None:
        """Move the present position towards the goal up to time ``t``; run the watchdog."""
        dt = max(0.0, t - self.t)
        self.t = max(self.t, t)
        wd = self.mem[98]
        if self.torque and 0 < wd <= 127 and t - self.bus_seen > wd * 0.020:
            self.trip_watchdog()
        moving = False
        if self.torque and dt > 0 and not self.stalled:
            goal = self.get("goal_position")
            step = self.speed_ticks_per_s() * dt
            err = goal - self.pos
            moving = abs(err) > 0.5
            self.pos = float(goal) if abs(err) <= step else self.pos + math.copysign(step, err)
        self._set("present_position", round(self.pos))
        self.mem[122] = 1 if moving else 0
        self._set("realtime_tick", int(t * 1000) % 32768)

    def trip_watchdog(self) -> None:
        """Bus Watchdog error state: stop where we are, refuse goals until 98 is written 0."""
        self.mem[98] = 0xFF
        self._set("goal_position", round(self.pos))

    def heard(self, t: float) -> None:
        """The servo was addressed at time ``t`` (feeds the Bus Watchdog)."""
        self.advance(t)
        self.bus_seen = t

    def hardware_fault(self, bits: int = OVERLOAD) -> None:
        """Raise a shutdown error: Hardware Error Status |= bits, torque cut."""
        self.mem[70] |= bits
        self.mem[64] = 0

    def reboot(self, t: float) -> None:
        """REBOOT: RAM back to defaults (torque off, errors cleared), position kept."""
        self.advance(t)
        self._reset_memory(keep_eeprom=True)
        self._set("goal_position", round(self.pos))
        self._set("present_position", round(self.pos))

    def read(self, address: int, length: int, t: float) -> tuple[int, bytes]:
        """(error byte, data) for a READ of ``length`` bytes at ``address``."""
        self.advance(t)
        if address + length > self.table.size or length == 0:
            return P.ERR_ACCESS | self.status_error(), b""
        return self.status_error(), bytes(self.mem[address:address + length])

    def write(self, address: int, data: bytes, t: float) -> int:
        """Apply a WRITE; returns the status error byte (0 or an error code, plus Alert)."""
        self.advance(t)
        alert = self.status_error()
        end = address + len(data)
        if not data or end > self.table.size:
            return P.ERR_ACCESS | alert
        touched = [r for r in self.table.registers.values() if r.address < end and address < r.address + r.size]
        for r in touched:
            if not r.writable:
                return P.ERR_ACCESS | alert
            if r.address < self.table.eeprom_end and self.torque:
                return P.ERR_ACCESS | alert
        new = bytearray(self.mem)
        new[address:end] = data
        for r in touched:
            if r.address < address or r.address + r.size > end:
                continue  # partially written register: raw bytes, no range check
            v = r.decode(bytes(new[r.address:r.address + r.size]))
            if r.name == "bus_watchdog" and self.mem[98] == 0xFF and v != 0:
                return P.ERR_DATA_RANGE | alert
            if not r.in_range(v):
                return P.ERR_DATA_RANGE | alert
            if r.name == "goal_position":
                if self.mem[98] == 0xFF:
                    return P.ERR_DATA_RANGE | alert  # watchdog error: goals refused
                if self.get("operating_mode") == 3 and not (
                        self.get("min_position_limit") <= v <= self.get("max_position_limit")):
                    return P.ERR_DATA_RANGE | alert
            if r.name == "torque_enable" and v == 1 and self.mem[70]:
                return P.ERR_RESULT_FAIL | alert  # shutdown error: only REBOOT restores torque
        self.mem[:] = new
        return alert

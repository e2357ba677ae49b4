"""Dynamixel control tables as data: register name -> address, size, access, area, range.

Values are integers as stored; ``signed`` registers are two's complement on the wire and
:meth:`Register.decode` returns the signed value. Units are in ``unit`` (e.g. "0.229 rpm").
EEPROM registers (address < ``eeprom_end``) can only be written with torque off.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from motion2robot.errors import RobotConfigError


@dataclass(frozen=True)
class Register:
    name: str
    address: int
    size: int  # bytes: 1, 2 or 4
    writable: bool
    default: int = 0
    low: int | None = None  # inclusive range a write must respect (None: whole width)
    high: int | None = None
    signed: bool = False
    unit: str = ""

    def encode(self, value: int) -> bytes:
        """Little-endian bytes of ``value`` (negative values as two's complement)."""
        return (int(value) & ((1 << (8 * self.size)) - 1)).to_bytes(self.size, "little")

    def decode(self, raw: bytes | int) -> int:
        """Integer value from little-endian bytes or an unsigned int, sign applied if signed."""
        v = int.from_bytes(bytes(raw), "little") if not isinstance(raw, int) else int(raw)
        if self.signed and v >= 1 << (8 * self.size - 1):
            v -= 1 << (8 * self.size)
        return v

    def in_range(self, value: int) -> bool:
        lo = self.low if self.low is not None else (-(1 << (8 * self.size - 1)) if self.signed else 0)
        hi = self.high if self.high is not None else ((1 << (8 * self.size - 1)) - 1 if self.signed else (1 << (8 * self.size)) - 1)
        return lo <= value <= hi


@dataclass(frozen=True)
class ControlTable:
    """One servo model: model number, registers by name, EEPROM boundary, feature flags.

    ``fast_sync_read_firmware``: the lowest firmware version that answers Fast Sync Read (0x8A)."""

    model: str
    model_number: int
    registers: Mapping[str, Register]
    eeprom_end: int
    size: int
    fast_sync_read_firmware: int
    ticks_per_rev: int = 4096
    velocity_unit_rpm: float = 0.229

    def __getitem__(self, name: str) -> Register:
        try:
            return self.registers[name]
        except KeyError:
            raise RobotConfigError(f"register '{name}' is not in the {self.model} control table; "
                                   f"use one of {', '.join(self.registers)}") from None


def _x_series(model: str, model_number: int, velocity_limit: int) -> ControlTable:
    R = Register
    regs = [
        # EEPROM (torque must be off to write)
        R("model_number", 0, 2, False, model_number),
        R("model_information", 2, 4, False, 0),
        R("firmware_version", 6, 1, False, 48),
        R("id", 7, 1, True, 1, 0, 252),
        R("baud_rate", 8, 1, True, 1, 0, 7),
        R("return_delay_time", 9, 1, True, 250, 0, 254, unit="2 us"),
        R("drive_mode", 10, 1, True, 0, 0, 13),
        R("operating_mode", 11, 1, True, 3, 0, 16),
        R("secondary_id", 12, 1, True, 255, 0, 255),
        R("protocol_type", 13, 1, True, 2, 1, 2),
        R("homing_offset", 20, 4, True, 0, -1044479, 1044479, signed=True, unit="tick"),
        R("moving_threshold", 24, 4, True, 10, 0, 1023, unit="0.229 rpm"),
        R("temperature_limit", 31, 1, True, 80, 0, 100, unit="C"),
        R("max_voltage_limit", 32, 2, True, 160, 95, 160, unit="0.1 V"),
        R("min_voltage_limit", 34, 2, True, 95, 95, 160, unit="0.1 V"),
        R("pwm_limit", 36, 2, True, 885, 0, 885),
        R("current_limit", 38, 2, True, 1193, 0, 1193, unit="2.69 mA"),
        R("velocity_limit", 44, 4, True, velocity_limit, 0, 1023, unit="0.229 rpm"),
        R("max_position_limit", 48, 4, True, 4095, 0, 4095, unit="tick"),
        R("min_position_limit", 52, 4, True, 0, 0, 4095, unit="tick"),
        R("startup_configuration", 60, 1, True, 0, 0, 3),
        R("shutdown", 63, 1, True, 52, 0, 255),
        # RAM
        R("torque_enable", 64, 1, True, 0, 0, 1),
        R("led", 65, 1, True, 0, 0, 1),
        R("status_return_level", 68, 1, True, 2, 0, 2),
        R("registered_instruction", 69, 1, False, 0),
        R("hardware_error_status", 70, 1, False, 0),
        R("velocity_i_gain", 76, 2, True, 1920, 0, 16383),
        R("velocity_p_gain", 78, 2, True, 100, 0, 16383),
        R("position_d_gain", 80, 2, True, 0, 0, 16383),
        R("position_i_gain", 82, 2, True, 0, 0, 16383),
        R("position_p_gain", 84, 2, True, 800, 0, 16383),
        R("feedforward_2nd_gain", 88, 2, True, 0, 0, 16383),
        R("feedforward_1st_gain", 90, 2, True, 0, 0, 16383),
        R("bus_watchdog", 98, 1, True, 0, 0, 127, unit="20 ms"),
        R("goal_pwm", 100, 2, True, 885, -885, 885, signed=True),
        R("goal_current", 102, 2, True, 1193, -1193, 1193, signed=True, unit="2.69 mA"),
        R("goal_velocity", 104, 4, True, 0, -1023, 1023, signed=True, unit="0.229 rpm"),
        R("profile_acceleration", 108, 4, True, 0, 0, 32767),
        R("profile_velocity", 112, 4, True, 0, 0, 32767, unit="0.229 rpm"),
        R("goal_position", 116, 4, True, 2048, signed=True, unit="tick"),
        R("realtime_tick", 120, 2, False, 0, unit="ms"),
        R("moving", 122, 1, False, 0),
        R("moving_status", 123, 1, False, 0),
        R("present_pwm", 124, 2, False, 0, signed=True),
        R("present_current", 126, 2, False, 0, signed=True, unit="2.69 mA"),
        R("present_velocity", 128, 4, False, 0, signed=True, unit="0.229 rpm"),
        R("present_position", 132, 4, False, 2048, signed=True, unit="tick"),
        R("velocity_trajectory", 136, 4, False, 0, signed=True),
        R("position_trajectory", 140, 4, False, 0, signed=True),
        R("present_input_voltage", 144, 2, False, 120, unit="0.1 V"),
        R("present_temperature", 146, 1, False, 30, unit="C"),
    ]
    return ControlTable(model, model_number, MappingProxyType({r.name: r for r in regs}),
                        eeprom_end=64, size=147, fast_sync_read_firmware=45)


#: Hardware Error Status bits (register 70) -> meaning.
HARDWARE_ERROR_BITS = {0: "input voltage error", 2: "overheating", 3: "motor encoder error",
                       4: "electrical shock", 5: "overload"}

#: Baud Rate register (8) value -> bits per second.
BAUD_RATES = {0: 9600, 1: 57600, 2: 115200, 3: 1_000_000, 4: 2_000_000, 5: 3_000_000, 6: 4_000_000, 7: 4_500_000}

TABLES: Mapping[str, ControlTable] = MappingProxyType({
    "XM430-W350": _x_series("XM430-W350", 1020, 200),
    "XM430-W210": _x_series("XM430-W210", 1030, 330),
})


def control_table(model: str) -> ControlTable:
    """The control table of a servo model name (e.g. "XM430-W350")."""
    try:
        return TABLES[model]
    except KeyError:
        raise RobotConfigError(f"servo model '{model}' has no control table; use one of "
                               f"{', '.join(TABLES)} in the robot config's [servos] model") from None


def model_name(model_number: int) -> str:
    """Model name for a model number, or 'model <n>' if unknown."""
    for t in TABLES.values():
        if t.model_number == model_number:
            return t.model
    return f"model {model_number}"


def describe_hardware_error(status: int) -> str:
    """'overload, overheating' for a Hardware Error Status value; 'none' for 0."""
    names = [name for bit, name in HARDWARE_ERROR_BITS.items() if status & (1 << bit)]
    unknown = status & ~sum(1 << b for b in HARDWARE_ERROR_BITS)
    if unknown:
        names.append(f"bits 0x{unknown:02X}")
    return ", ".join(names) if names else "none"

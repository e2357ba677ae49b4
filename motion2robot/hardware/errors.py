"""Typed hardware errors. Each names the servo (ID and joint when known) and the cause.

They are :class:`~motion2robot.errors.UserError` subclasses: one line, printed by the CLI with
exit code 2, because the fix is on the user's side (cable, power, port, configuration).
"""

from __future__ import annotations

from motion2robot.errors import UserError


class HardwareError(UserError):
    """A problem talking to servos or with their state; ``servo_id`` is None for bus-wide ones."""

    def __init__(self, message: str, servo_id: int | None = None):
        super().__init__(message)
        self.servo_id = servo_id


class PortError(HardwareError):
    """The serial port cannot be opened, configured, or was closed under us."""


class CommError(HardwareError):
    """No valid status packet (timeout, corrupt packet, CRC) after the bounded retries."""


class ServoStatusError(HardwareError):
    """A servo answered with error bits in its status packet (access, range, CRC, ...)."""


class HardwareAlert(HardwareError):
    """A servo raised the Alert bit; the message decodes its Hardware Error Status."""


class SafetyError(HardwareError):
    """The safety guard refuses to start or continue (pose unreadable, out of limits, ...)."""

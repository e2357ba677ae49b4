"""Typed hardware errors. Each names the servo (ID and joint when known) and the cause.

They are :class:`~motion2robot.errors.UserError` subclasses: one line, printed by the CLI with
exit code 2, because the fix is on the user's side (cable, power, port, configuration).
"""

from __future__ import annotations

from motion2robot.errors import UserError


class HardwareError(UserError):
    """A problem talking to servos or with their state; ``servo_id`` is None for bus-wide ones.
    ``kind`` names the fault in telemetry and in the stream's error line."""

    kind = "hardware"

    def __init__(self, message: str, servo_id: int | None = None):
        super().__init__(message)
        self.servo_id = servo_id


class PortError(HardwareError):
    """The serial port cannot be opened, configured, or was closed under us."""

    kind = "port"


class CommError(HardwareError):
    """No valid status packet (timeout, corrupt packet, CRC) after the bounded retries."""

    kind = "comm"


class ServoStatusError(HardwareError):
    """A servo answered with error bits in its status packet (access, range, CRC, ...)."""

    kind = "status"


class HardwareAlert(HardwareError):
    """A servo raised the Alert bit or reports a Hardware Error Status; the message decodes it."""

    kind = "hardware_error"


class SafetyError(HardwareError):
    """The safety guard refuses to start or continue (pose unreadable, out of limits, ...)."""

    kind = "safety"


class WatchdogFault(HardwareError):
    """The servos stopped obeying because their Bus Watchdog tripped (read back from the servos,
    or inferred from a silence on the bus longer than the watchdog, e.g. a stalled process)."""

    kind = "watchdog"


class DivergenceFault(HardwareError):
    """Present positions stayed further from the commanded goals than servo compliance and
    tracking lag explain: the servo stalled, slipped or stopped obeying."""

    kind = "divergence"

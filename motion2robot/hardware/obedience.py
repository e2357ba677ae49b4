"""Do the servos still obey? The checks the streamer runs on what comes back from the bus.

The guard decides what may be sent; this module decides whether the servos are still doing what
was sent. Each of these is a fault (a typed :class:`~motion2robot.hardware.errors.HardwareError`):

- **Bus silent longer than the Bus Watchdog** (host clock, checked after every transfer against
  the start of the previous one, so a stall before or during a transfer counts): the servos
  have stopped themselves (a stalled process: SIGSTOP/SIGCONT, swap, a debugger).
- **Bus Watchdog state** (register 98, read back alternately with Hardware Error Status every
  ``state_every`` ticks, 0.25 s, so each every 0.5 s; in a tick with half a period to spare, or
  at the latest ``state_every`` ticks late, so the extra read does not make ticks overrun): 255
  means it tripped; any other value than the one armed means the servo is not guarded as
  configured.
- **Hardware Error Status** non-zero (also caught on every tick by the Alert bit).
- **Present position diverging from the goal** by more than servo compliance and tracking lag
  explain, for ``persist_ticks`` ticks in a row (the servo is stalled, blocked or refusing
  goals). Per joint, in radians::

      threshold = compliance + 2 * velocity_limit / rate + 2 ticks

  ``compliance`` = torque limit / position gain kp (the robot config's ``torque`` and ``kp``:
  a position servo pushed by the largest load it resists sits that far off its goal; OP3:
  4.1 N*m / 21.1 N*m/rad = 0.19 rad), ``velocity_limit / rate`` is the guard's largest step per
  tick (the present is read right after a new goal is written, so it lags by up to one step, one
  more for the transfer), 2 ticks cover encoder and goal rounding. At 100 Hz on the OP3:
  0.19 + 0.096 + 0.003 = 0.29 rad. ``max_divergence`` replaces the formula by a fixed value.
  ``persist_ticks`` = the ticks in 50 ms, at least 2. A tick in which the servo moved at least
  two encoder ticks towards its goal does not count: a servo catching up (slower than the guard
  lets the goals move, e.g. its own Velocity Limit register set lower) is obeying; one that
  stands still or moves away is not.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from motion2robot.hardware.calibration import Calibration
from motion2robot.hardware.control_table import describe_hardware_error
from motion2robot.hardware.errors import DivergenceFault, HardwareAlert, WatchdogFault
from motion2robot.hardware.limits import JointLimits

#: Compliance assumed when the robot config gives no torque/kp (XM430-W350 at 12 V: 4.1 / 21.1).
DEFAULT_COMPLIANCE_RAD = 0.2
STATE_CHECK_S = 0.25  # one of the two state registers is read back every 0.25 s (each every 0.5 s)
PERSIST_S = 0.05
STATE_REGISTERS = ("bus_watchdog", "hardware_error_status")


def hardware_alert(servo_id: int, joint: str, status: int | str) -> HardwareAlert:
    """The fault of a servo reporting Hardware Error Status ``status`` (or why it is unreadable)."""
    what = status if isinstance(status, str) else \
        f"Hardware Error Status 0x{status:02X} ({describe_hardware_error(status)})"
    return HardwareAlert(f"servo {servo_id} ({joint}): {what}; the servo cut its torque: remove the cause, then "
                         f"'motion2robot servos reboot --id {servo_id}'", servo_id)


@dataclass(frozen=True, eq=False)
class ObedienceLimits:
    """Thresholds for one stream: ``divergence`` (n,) rad per joint, ``persist_ticks``,
    ``watchdog_s`` (0 = no watchdog armed), ``watchdog_units`` (register value armed),
    ``state_every`` (ticks between reads of a state register)."""

    divergence: np.ndarray
    persist_ticks: int
    watchdog_s: float
    watchdog_units: int
    state_every: int

    @classmethod
    def derive(cls, limits: JointLimits, cal: Calibration, rate_hz: float, watchdog_units: int,
               max_divergence: float | None = None) -> ObedienceLimits:
        """From the joint limits (calibration order) and the rate (Hz); see the module docstring."""
        if max_divergence is not None:
            if not (math.isfinite(max_divergence) and max_divergence > 0):
                raise ValueError(f"max_divergence must be a finite angle > 0 rad, got {max_divergence}")
            div = np.full(len(limits.names), float(max_divergence))
        else:
            comp = limits.compliance if limits.compliance is not None else np.full(len(limits.names),
                                                                                   DEFAULT_COMPLIANCE_RAD)
            div = comp + 2.0 * limits.velocity / rate_hz + 2.0 / cal.ticks_per_rad
        return cls(div, max(2, math.ceil(PERSIST_S * rate_hz - 1e-9)), watchdog_units * 0.020, int(watchdog_units),
                   max(1, round(STATE_CHECK_S * rate_hz)))


class ObedienceMonitor:
    """Runs the checks of :class:`ObedienceLimits` for the servos ``ids`` (calibration order)."""

    def __init__(self, limits: ObedienceLimits, cal: Calibration, ids: Sequence[int]):
        self.limits = limits
        self.cal = cal
        self.ids = list(ids)
        self.over = np.zeros(len(self.ids), dtype=np.int64)
        self.last_present: np.ndarray | None = None
        self.last_heard: float | None = None
        self.next_state = limits.state_every  # tick count at which a state read is due
        self.state_turn = 0

    def _who(self, k: int) -> str:
        return f"servo {self.ids[k]} ({self.cal.joints[k]})"

    def heard(self, now: float) -> None:
        """The bus carried traffic at ``now`` (``clock()`` s): the servos' watchdogs were fed."""
        self.last_heard = now

    def check_silence(self, now: float) -> None:
        """After a transfer: a silence longer than the watchdog means the servos stopped."""
        if self.last_heard is None or self.limits.watchdog_s <= 0:
            return
        gap = now - self.last_heard
        if gap > self.limits.watchdog_s:
            self.last_heard = now  # reported once; the stop path talks to the bus again
            raise WatchdogFault(f"the bus was silent for {gap * 1e3:.0f} ms, longer than the Bus Watchdog "
                                f"({self.limits.watchdog_s * 1e3:.0f} ms): this process was stalled (stopped, "
                                "swapped out or starved of CPU) and the servos stopped obeying; find what stalled "
                                "it (--realtime helps on a busy machine) and stream again")

    def check_divergence(self, goal: np.ndarray, present: np.ndarray) -> None:
        """Goal and present (ticks, calibration order) of this tick."""
        err = np.abs(self.cal.to_radians(present) - self.cal.to_radians(goal))
        over = err > self.limits.divergence
        present = np.asarray(present, dtype=np.float64)
        if self.last_present is not None:  # moving towards the goal: catching up, obeying
            towards = np.sign(np.asarray(goal, dtype=np.float64) - self.last_present) * (present - self.last_present)
            over &= towards < 2.0
        self.last_present = present
        self.over = np.where(over, self.over + 1, 0)
        bad = np.where(self.over >= self.limits.persist_ticks)[0]
        if bad.size:
            k = int(bad[np.argmax(err[bad])])
            raise DivergenceFault(
                f"{self._who(k)}: present position {float(self.cal.to_radians(present)[k]):.3f} rad stayed "
                f"{err[k]:.3f} rad from its goal {float(self.cal.to_radians(goal)[k]):.3f} rad for "
                f"{int(self.over[k])} ticks (more than the {self.limits.divergence[k]:.3f} rad that compliance and "
                "tracking lag explain); the servo is blocked, overloaded or not obeying: check for a collision or "
                "a load, and the servo with 'motion2robot servos scan'", self.ids[k])

    def state_register(self, tick: int, spare_time: bool = True) -> str | None:
        """The state register to read back at the ``tick``-th tick (None: none now). A due read
        waits for a tick with ``spare_time``, at most ``state_every`` ticks."""
        every = self.limits.state_every
        if tick < self.next_state or (not spare_time and tick < self.next_state + every):
            return None
        self.next_state = tick + every
        self.state_turn += 1
        return STATE_REGISTERS[(self.state_turn - 1) % len(STATE_REGISTERS)]

    def check_state(self, register: str, values: Mapping[int, int]) -> None:
        """Values of a state register read back from every servo."""
        for k, i in enumerate(self.ids):
            v = int(values[i])
            if register == "hardware_error_status" and v:
                raise hardware_alert(i, self.cal.joints[k], v)
            if register == "bus_watchdog" and v != self.limits.watchdog_units:
                what = ("tripped (register 98 reads 255): the servo stopped and refuses goals" if v & 0x80 else
                        f"reads {v} instead of the {self.limits.watchdog_units} armed")
                raise WatchdogFault(f"{self._who(k)}: Bus Watchdog {what}; the bus was silent too long for it "
                                    "(a stalled host, a loose cable) or something else wrote it; check the cable "
                                    "and stream again", i)

"""Stream a RobotMotion to servos at a fixed rate.

Per tick (absolute deadlines ``t0 + k / rate``): interpolate the motion at the tick's play time
(:mod:`~motion2robot.hardware.goals`, the schedule the physics rollout of ``check`` plays too), let
the :class:`~motion2robot.hardware.guard.SafetyGuard` turn it into goal ticks, sync-write the goals,
sync-read present positions (fast sync read where supported) and their status bytes, write a
telemetry line. Missed deadlines are counted as overruns and skipped (no catch-up burst).
Whether the servos still obey is checked on every tick by
:class:`~motion2robot.hardware.obedience.ObedienceMonitor` (bus silence longer than the Bus
Watchdog, watchdog and Hardware Error Status read back, present diverging from the goal); each
is a fault, and a stream with a fault never ends as "end". The Bus Watchdog is set from the rate
(or refused) by :meth:`TorquePolicy.for_rate`. Waits are sliced so that a signal acts within
20 ms at any rate.

Phases: ramp_in (present pose -> first frame at the ramp speed), play, ramp_out (to the rest
pose, if given), hold, then torque off. Ctrl-C/SIGTERM and faults (typed hardware errors,
Alert bits) go through the same stop path (:class:`~motion2robot.hardware.policy.TorquePolicy`):
hold or torque off at once; torque-off is attempted on every servo even when some fail, and
the port is always closed.
"""

from __future__ import annotations

import gc
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from motion2robot.hardware.bus import ServoBus
from motion2robot.hardware.calibration import Calibration
from motion2robot.hardware.control_table import describe_hardware_error
from motion2robot.hardware.errors import HardwareAlert, HardwareError, SafetyError
from motion2robot.hardware.goals import play_target
from motion2robot.hardware.guard import SafetyGuard
from motion2robot.hardware.limits import JointLimits
from motion2robot.hardware.obedience import STATE_REGISTERS, ObedienceLimits, ObedienceMonitor, hardware_alert
from motion2robot.hardware.policy import TorquePolicy
from motion2robot.hardware.report import StreamReport
from motion2robot.hardware.signals import StopSignals
from motion2robot.hardware.telemetry import TelemetryWriter
from motion2robot.hardware.timing import (
    LoopFigures,
    clock,
    realtime_priority,
    sleep_until,
)
from motion2robot.hardware.trajectory import joint_trajectory, sample
from motion2robot.robot.servo_map import ServoMap
from motion2robot.robot_motion import RobotMotion

BusFactory = Callable[[], ServoBus]
__all__ = ["BusFactory", "StreamReport", "Streamer", "sample", "stream_motion", "stream_to_virtual_chain"]


class _Stop(Exception):
    def __init__(self, reason: str, message: str = ""):
        super().__init__(message or reason)
        self.reason = reason


class Streamer:
    """One streaming session; see :func:`stream_motion`."""

    def __init__(self, motion: RobotMotion, limits: JointLimits, servo_map: ServoMap, bus_factory: BusFactory | None,
                 *, rate_hz: float, loop: bool, policy: TorquePolicy, telemetry_path: str | Path | None,
                 offsets: Mapping[str, int] | None, rest_pose: np.ndarray | None, max_seconds: float | None,
                 realtime: bool = False, max_divergence: float | None = None):
        self.cal = Calibration.from_servo_map(servo_map, offsets)
        self.ids = [int(i) for i in self.cal.ids]
        self.limits = limits.select(self.cal.joints)
        self.traj = joint_trajectory(motion, self.cal.joints)
        self.fps = motion.fps
        self.duration = (self.traj.shape[0] - 1) / self.fps
        self.rate = float(rate_hz)
        self.dt = 1.0 / self.rate
        self.loop = loop
        self.watchdog_note = ""
        if bus_factory is not None:  # a dry run arms no watchdog: any rate will do
            policy, self.watchdog_note = policy.for_rate(self.rate)
        self.policy = policy
        wd_units = policy.watchdog_units if bus_factory is not None else 0
        self.monitor = ObedienceMonitor(ObedienceLimits.derive(self.limits, self.cal, self.rate, wd_units, max_divergence),
                                        self.cal, self.ids)
        self.guard = SafetyGuard(self.limits, self.cal, self.rate, policy.ramp_speed)
        self.bus_factory = bus_factory
        self.rest = None if rest_pose is None else np.asarray(rest_pose, dtype=np.float64)
        self.max_seconds = max_seconds
        self.realtime = realtime
        self.telemetry_path = str(telemetry_path) if telemetry_path else None
        self.tel: TelemetryWriter | None = None
        self.bus: ServoBus | None = None
        self.faults: list[str] = []
        self.fault_kind: str | None = None
        self.fault_tick: int | None = None
        self.starts: list[float] = []
        self.overruns = 0
        self.recovered = 0
        self.started = False
        self.k = 0
        self.header = {"joints": list(self.cal.joints), "ids": self.ids, "rate_hz": self.rate,
                       "motion": {"robot": motion.robot, "frames": motion.num_frames, "fps": motion.fps,
                                  "source": str(motion.meta.get("source", ""))},
                       "policy": policy.__dict__, "dry_run": bus_factory is None,
                       "divergence_rad": [round(float(x), 4) for x in self.monitor.limits.divergence],
                       "watchdog_note": self.watchdog_note}

    # -- set-up ---------------------------------------------------------------------------
    def _fault(self, err: BaseException) -> None:
        msg = str(err)
        kind = getattr(err, "kind", "hardware")
        self.faults.append(msg)
        if self.fault_tick is None:
            self.fault_tick, self.fault_kind = self.k, kind
        if self.tel:
            self.tel.event("fault", msg, getattr(err, "servo_id", None), tick=self.k, fault=kind)

    def _alert_error(self, ids: list[int]) -> HardwareAlert:
        i = ids[0]
        assert self.bus is not None
        try:
            hes: int | str = self.bus.read(i, "hardware_error_status")
        except HardwareError as err:
            hes = f"Alert bit set, Hardware Error Status unreadable ({err})"
        return hardware_alert(i, self.cal.joints[self.ids.index(i)], hes)

    def _present(self) -> np.ndarray:
        assert self.bus is not None
        r = self.bus.sync_read("present_position", self.ids)
        alerts = self.guard.check_status(r.status, self.ids)
        if alerts:
            raise self._alert_error(alerts)
        return np.array([r.values[i] for i in self.ids], dtype=np.int64)

    def _prepare(self) -> np.ndarray:
        """Checks before torque: every servo answers, no hardware error, pose readable."""
        if self.bus is None:
            first = self.traj[0]
            return self.guard.start(np.where(np.isfinite(first), self.cal.ticks_float(np.nan_to_num(first)),
                                             self.cal.center + self.cal.offset))
        found = {s.id: s for s in self.bus.scan(self.ids)}
        missing = [i for i in self.ids if i not in found]
        if missing:
            names = ", ".join(f"{i} ({self.cal.joints[self.ids.index(i)]})" for i in missing)
            raise SafetyError(f"refusing to start: servos {names} do not answer; check cables, power and IDs "
                              "with 'motion2robot servos scan'", missing[0])
        bad = [s for s in found.values() if s.hardware_error_status]
        if bad:
            s = bad[0]
            raise HardwareAlert(f"refusing to start: servo {s.id} reports Hardware Error Status 0x{s.hardware_error_status:02X} "
                                f"({describe_hardware_error(s.hardware_error_status or 0)}); fix it, then "
                                f"'motion2robot servos reboot --id {s.id}'", s.id)
        try:
            present = self._present()
        except HardwareError as err:
            raise SafetyError(f"refusing to start: cannot read the present pose ({err})", err.servo_id) from err
        goal0 = self.guard.start(present)
        self.bus.sync_write("goal_position", dict(zip(self.ids, goal0.tolist())))
        if self.policy.watchdog_units:
            self.bus.sync_write("bus_watchdog", {i: 0 for i in self.ids})  # clears a latched watchdog error
        failed = {i: e for i, e in self.bus.set_torque(self.ids, True).items() if e}
        if failed:
            raise SafetyError(f"refusing to start: torque on failed ({next(iter(failed.values()))})", next(iter(failed)))
        if self.policy.watchdog_units:
            self.bus.sync_write("bus_watchdog", {i: self.policy.watchdog_units for i in self.ids})
        self.monitor.heard(clock())
        return goal0

    def _check_state(self, registers: tuple[str, ...]) -> None:
        """Read state registers back from every servo (Bus Watchdog, Hardware Error Status)."""
        assert self.bus is not None
        for reg in registers:
            self.monitor.check_state(reg, self._sent(self.bus.sync_read, reg, self.ids).values)

    def _sent(self, call: Callable[..., Any], *args: Any) -> Any:
        """One bus transfer; afterwards, a bus possibly silent for longer than the watchdog since the
        previous transfer began (the process stopped before or during this one) is a fault."""
        start = clock()
        out = call(*args)
        self.monitor.check_silence(clock())
        self.monitor.heard(start)
        return out

    # -- loop -----------------------------------------------------------------------------
    def _tick(self, target: np.ndarray | None, ramp: bool, phase: str, t0: float) -> np.ndarray:
        self.starts.append(clock())
        goal = self.guard.next_goal(target, ramp)
        present = None
        if self.bus is not None:
            self._sent(self.bus.sync_write, "goal_position", dict(zip(self.ids, goal.tolist())))
            present = self._sent(self._present)
            spare = clock() < t0 + (self.k + 0.5) * self.dt  # half a period left: an extra read will not overrun
            reg = self.monitor.state_register(len(self.starts), spare)
            if reg:
                self._check_state((reg,))
            for msg in self.bus.recoveries():
                self.recovered += 1
                if self.tel:
                    self.tel.event("recovered", msg, tick=self.k)
        if self.tel:
            now = self.starts[-1]
            period = now - self.starts[-2] if len(self.starts) > 1 else 0.0
            self.tel.tick(self.k, now - t0, period, now - (t0 + self.k * self.dt), phase,
                          self.cal.to_radians(goal), None if present is None else self.cal.to_radians(present))
        if present is not None:
            self.monitor.check_divergence(goal, present)
        return goal

    def _wait_next(self, t0: float, interrupted: Callable[[], bool]) -> bool:
        """Sleep to the next tick's deadline; False if ``interrupted()`` came first."""
        self.k += 1
        now = clock()
        if now > t0 + self.k * self.dt:
            self.overruns += 1
            self.k = int((now - t0) / self.dt) + 1
        return sleep_until(t0 + self.k * self.dt, interrupted=interrupted)

    def _run(self, sig: StopSignals, t0: float) -> str:
        """Ramp in, play, ramp out, hold on end; returns the stop reason or raises _Stop."""
        phase = "ramp_in"
        play_k0 = 0  # the first play tick; play tick k asks for the motion at k / rate (hardware.goals)
        hold_until = None
        while True:
            if sig.count:
                raise _Stop("interrupt")
            now = clock()
            if self.max_seconds is not None and now - t0 >= self.max_seconds and phase == "play":
                phase = "ramp_out" if self.rest is not None and self.policy.ramp_out else "hold"
            if phase == "ramp_in":
                target, ramp = self.traj[0], True
            elif phase == "play":
                target, ramp = play_target(self.traj, self.fps, self.rate, self.k - play_k0, self.loop), False
                if target is None:
                    phase = "ramp_out" if self.rest is not None and self.policy.ramp_out else "hold"
            if phase == "ramp_out":
                target, ramp = self.rest, True
            if phase == "hold":
                if hold_until is None:
                    hold_until = now + self.policy.on_end
                elif now >= hold_until:  # the hold is over: no tick off the schedule, a last state read
                    if self.bus is not None:
                        self._check_state(STATE_REGISTERS)  # never "end" with servos that stopped obeying
                    return "end"
                target, ramp = None, False
            self._tick(target, ramp, phase, t0)
            if phase == "ramp_in" and self.guard.reached(self.traj[0]):
                phase, play_k0 = "play", self.k + 1
            elif phase == "ramp_out" and self.guard.reached(self.rest):
                phase = "hold"
            until = hold_until
            self._wait_next(t0, lambda: bool(sig.count) or (until is not None and clock() >= until))

    def _hold(self, seconds: float, sig: StopSignals, t0: float) -> None:
        """Keep the last goal for ``seconds`` (reading the bus); a 2nd Ctrl-C cuts it short."""
        if seconds <= 0:
            return
        first = sig.count
        end = clock() + seconds
        while clock() < end and sig.count <= first:
            if not self._wait_next(t0, lambda: sig.count > first or clock() >= end):
                break
            self._tick(None, False, "hold", t0)

    def _torque_off(self) -> tuple[dict[int, bool | None], list[str]]:
        if self.bus is None:
            return {}, []
        if not self.bus.is_open:
            wd = (f"the Bus Watchdog stops the servos {self.policy.watchdog_units * 20} ms after the last packet"
                  if self.policy.watchdog_units and self.started else "check the servos by hand")
            return dict.fromkeys(self.ids), [f"the port is closed: torque-off could not be sent; {wd}"]
        result = self.bus.set_torque(self.ids, False)
        retry = [i for i, e in result.items() if e]
        if retry:
            result.update(self.bus.set_torque(retry, False))
        errors = [str(e) for e in result.values() if e]
        state: dict[int, bool | None] = {}
        for i in self.ids:
            try:
                state[i] = bool(self.bus.read(i, "torque_enable"))
                if self.policy.watchdog_units:
                    self.bus.write(i, "bus_watchdog", 0)
            except HardwareError:
                state.setdefault(i, None)
        return state, errors

    def run(self) -> StreamReport:
        reason, torque_after, off_errors = "error", {}, []
        t0 = clock()
        gc_was_enabled = gc.isenabled()
        gc.collect()
        gc.disable()  # a full collection can stall a tick for tens of ms; re-enabled below
        try:
            with StopSignals() as sig, realtime_priority(self.realtime) as rt:
                self.header["realtime"] = rt.granted
                if self.telemetry_path:
                    self.tel = TelemetryWriter(self.telemetry_path, self.header)
                try:
                    if self.bus_factory is not None:
                        self.bus = self.bus_factory()
                        self.bus.open()
                    self._prepare()
                    t0 = clock()
                    self.started = True
                    reason = self._run(sig, t0)
                except _Stop as stop:
                    reason = stop.reason
                    self._safe_hold(self.policy.on_interrupt, sig, t0)
                except HardwareError as err:
                    reason = "fault" if self.started else "refused"
                    self._fault(err)
                    if self.started:
                        self._safe_hold(self.policy.on_fault, sig, t0)
                finally:
                    try:
                        torque_after, off_errors = self._torque_off()
                    finally:
                        if self.bus is not None:
                            self.bus.close()
        finally:
            if gc_was_enabled:
                gc.enable()
            if reason == "end" and (self.faults or off_errors):  # never a success after a fault
                reason = "fault"
                self.fault_kind = self.fault_kind or "torque_off"
            figures = LoopFigures.from_starts(self.starts, self.dt, self.overruns)
            report = StreamReport(figures, reason, tuple(self.faults), torque_after, self.telemetry_path,
                                  self.bus_factory is None, self.k, self.fault_tick, tuple(off_errors),
                                  self.recovered, self.fault_kind, self.watchdog_note)
            if self.tel:
                self.tel.stop(reason=reason, tick=self.k, fault_tick=self.fault_tick, fault=self.fault_kind,
                              faults=list(self.faults),
                              torque={str(i): v for i, v in torque_after.items()}, torque_off_errors=off_errors,
                              figures=figures.__dict__)
                self.tel.close()
        return report

    def _safe_hold(self, seconds: float, sig: StopSignals, t0: float) -> None:
        try:
            self._hold(seconds, sig, t0)
        except HardwareError as err:
            self._fault(err)


def stream_motion(motion: RobotMotion, limits: JointLimits, servo_map: ServoMap, bus_factory: BusFactory | None, *,
                  rate_hz: float = 100.0, loop: bool = False, dry_run: bool = False,
                  telemetry_path: str | Path | None = None, policy: TorquePolicy | None = None,
                  offsets: Mapping[str, int] | None = None, rest_pose: np.ndarray | None = None,
                  max_seconds: float | None = None, realtime: bool = False,
                  max_divergence: float | None = None) -> StreamReport:
    """Stream ``motion`` to the servos of ``servo_map`` on the bus made by ``bus_factory``.

    ``limits``: joint limits (rad, rad/s) covering the servo map's joints; ``rest_pose``: angles
    (rad, servo-map joint order) to ramp to at the end (None: stay at the last frame);
    ``offsets``: calibration zero offsets (ticks by joint); ``dry_run``: no bus at all, the
    guard and timing run as if the servos started at the first frame; ``max_seconds``: stop
    playing after this long (useful with ``loop``); ``realtime``: run the loop under SCHED_FIFO
    when the OS allows it (root or CAP_SYS_NICE); ``max_divergence``: present-vs-goal distance
    (rad) that is a fault, instead of the one derived from compliance and the guard's step (see
    :mod:`motion2robot.hardware.obedience`). Hardware problems before the loop starts end with
    stop reason "refused"; the report never raises for hardware faults. A Bus Watchdog that the
    rate cannot keep fed is refused with UserError before anything is sent."""
    s = Streamer(motion, limits, servo_map, None if dry_run else bus_factory, rate_hz=rate_hz, loop=loop,
                 policy=policy or TorquePolicy(), telemetry_path=telemetry_path, offsets=offsets,
                 rest_pose=rest_pose, max_seconds=max_seconds, realtime=realtime, max_divergence=max_divergence)
    return s.run()


def stream_to_virtual_chain(motion: RobotMotion, limits: JointLimits, servo_map: ServoMap, *,
                            baud: int | None = None, rate_hz: float = 100.0, wire_time: bool = True,
                            start_pose: np.ndarray | None = None, latency_ms: float | None = None,
                            **kwargs: Any) -> StreamReport:
    """Start a virtual servo chain on a pty (one servo per servo-map entry, Return Delay Time 0),
    stream to it through DynamixelBus and the real dynamixel-sdk, tear it all down.

    ``start_pose``: the servos' initial angles (rad, servo-map order; default: the motion's first
    frame, so the ramp-in is immediate; pass zeros to watch a ramp from the servos' centre);
    ``latency_ms``: latency the SDK reply timeouts assume (default ``PTY_LATENCY_MS``); other
    keyword arguments go to :func:`stream_motion`."""
    from motion2robot.hardware.dynamixel_bus import DynamixelBus
    from motion2robot.hardware.virtual_chain import PTY_LATENCY_MS, VirtualChain

    cal = Calibration.from_servo_map(servo_map, kwargs.get("offsets"))
    baud = int(baud or servo_map.baud)
    if start_pose is None:
        lim = limits.select(cal.joints)
        start = np.clip(np.nan_to_num(joint_trajectory(motion, cal.joints)[0]), lim.lower, lim.upper)
    else:
        start = np.asarray(start_pose, dtype=np.float64)
    positions = dict(zip(cal.ids.tolist(), cal.to_ticks(start).tolist()))
    names = dict(zip(cal.ids.tolist(), cal.joints))
    with VirtualChain(cal.ids.tolist(), model=servo_map.model, baud=baud, wire_time=wire_time,
                      positions=positions) as chain:
        return stream_motion(motion, limits, servo_map,
                             lambda: DynamixelBus(chain.port_name, baud, servo_map.model, names=names,
                                                  latency_timer_ms=latency_ms or PTY_LATENCY_MS),
                             rate_hz=rate_hz, **kwargs)

"""Servos that stop obeying are faults (issue 20): a tripped Bus Watchdog, a stalled servo, a
stalled host process; the rate and the watchdog must agree; sub-tick velocity limits hold on
the wire; signals act within 100 ms at any rate."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.errors import InputFileError, UserError
from motion2robot.hardware.calibration import Calibration
from motion2robot.hardware.limits import JointLimits
from motion2robot.hardware.obedience import ObedienceLimits
from motion2robot.hardware.policy import TorquePolicy
from motion2robot.hardware.telemetry import read_telemetry
from motion2robot.hardware.virtual_chain import Fault, VirtualChain
from motion2robot.hardware.watchdog import min_watchdog_ms, watchdog_for_rate
from motion2robot.robot_motion import RobotMotion
from tests.test_hardware_stream import CAL, FAST, LIMITS, N, NAMES, motion, run, start_at


def ramp_motion(seconds: float = 1.5, amplitude: float = 0.9) -> np.ndarray:
    t = np.arange(int(seconds * 50) + 1) / 50.0
    return amplitude * np.minimum(t / seconds, 1.0)[:, None] * np.ones(N)[None, :]


def test_watchdog_follows_the_rate_or_is_refused():
    assert min_watchdog_ms(100) == 40 and min_watchdog_ms(5) == 420 and min_watchdog_ms(1) == 2020
    assert watchdog_for_rate(None, 100).ms == 100 and watchdog_for_rate(None, 100).note == ""
    w = watchdog_for_rate(None, 5)
    assert w.ms == 420 and "420 ms for 5 Hz" in w.note
    assert watchdog_for_rate(0, 0.001).ms == 0
    with pytest.raises(UserError, match="too short for --rate 5 Hz.*>= 420"):
        watchdog_for_rate(100, 5)
    with pytest.raises(UserError, match="too slow for the Bus Watchdog"):
        watchdog_for_rate(None, 0.5)
    assert TorquePolicy().for_rate(5)[0].watchdog_units == 21


def test_divergence_threshold_is_compliance_plus_two_steps():
    lim = ObedienceLimits.derive(LIMITS, CAL, 100.0, 5)
    assert np.allclose(lim.divergence, 0.2 + 2 * 6.0 / 100.0 + 2 / CAL.ticks_per_rad)
    assert lim.persist_ticks == 5 and lim.watchdog_s == pytest.approx(0.1) and lim.state_every == 25
    with_c = JointLimits(LIMITS.names, LIMITS.lower, LIMITS.upper, LIMITS.velocity, np.full(N, 4.1 / 21.1))
    assert np.allclose(ObedienceLimits.derive(with_c, CAL, 5.0, 21).divergence, 4.1 / 21.1 + 2 * 1.2 + 2 / CAL.ticks_per_rad)
    assert np.allclose(ObedienceLimits.derive(LIMITS, CAL, 100.0, 5, max_divergence=0.05).divergence, 0.05)


def _fault_run(tmp_path: Path, fault: Fault, q: np.ndarray, **kw):
    with VirtualChain(CAL.ids.tolist(), baud=1_000_000, positions=start_at(q[0])) as chain:
        chain.inject(fault)
        rep, tel = run(chain, motion(q), tmp_path, **kw)
        snap = chain.snapshot()
    return rep, tel, snap


def test_a_servo_catching_up_is_obeying_one_standing_still_is_not():
    """Far from its goal, a servo that moves towards it every tick (slower than the goals move) is
    never a divergence fault; the same error with the servo standing still is, after persist_ticks."""
    from motion2robot.hardware.errors import DivergenceFault
    from motion2robot.hardware.obedience import ObedienceMonitor

    lim = ObedienceLimits.derive(LIMITS, CAL, 100.0, 5)
    n = len(CAL.joints)
    goal = np.full(n, 3000.0)
    far = goal - 1.5 * lim.divergence.max() * CAL.ticks_per_rad
    catching = ObedienceMonitor(lim, CAL, CAL.ids.tolist())
    for k in range(5 * lim.persist_ticks):
        catching.check_divergence(goal, far + 3.0 * k)  # 3 encoder ticks closer every tick
    stuck = ObedienceMonitor(lim, CAL, CAL.ids.tolist())
    with pytest.raises(DivergenceFault):
        for _ in range(lim.persist_ticks + 1):
            stuck.check_divergence(goal, far)


def test_a_tripped_bus_watchdog_is_a_fault(tmp_path):
    """A servo whose watchdog tripped answers normally but refuses goals: read back, it is a fault."""
    rep, tel, snap = _fault_run(tmp_path, Fault("watchdog", 7, after_writes=5), np.zeros((100, N)))
    assert rep.stop_reason == "fault" and rep.fault_kind == "watchdog", rep.describe()
    assert "servo 7 (r_hip_yaw)" in rep.faults[0] and "tripped" in rep.faults[0]
    assert tel.stop["fault"] == "watchdog" and tel.events[0]["fault"] == "watchdog"
    assert rep.fault_tick <= 5 + 4 * 25 + 2  # found by a read-back of register 98 (every 50 ticks, <= 25 late)
    assert not any(s["torque"] for s in snap.values())


def test_a_stalled_servo_is_a_divergence_fault(tmp_path):
    rep, tel, snap = _fault_run(tmp_path, Fault("stall", 13, after_writes=10), ramp_motion())
    assert rep.stop_reason == "fault" and rep.fault_kind == "divergence", rep.describe()
    assert "servo 13 (r_knee)" in rep.faults[0] and "from its goal" in rep.faults[0]
    # the fault comes once the command is 0.32 rad away and has stayed so for 5 ticks
    threshold = 0.2 + 2 * 6.0 / 100.0 + 2 / CAL.ticks_per_rad
    cmd = np.array([t["cmd"][12] for t in tel.ticks])
    present = np.array([t["present"][12] for t in tel.ticks])
    assert np.sum(np.abs(cmd - present) > threshold + 1e-4) == 5 and np.all(np.abs(cmd - present)[-5:] > threshold - 1e-4)
    assert not any(s["torque"] for s in snap.values())


def test_no_false_fault_when_the_servos_follow(tmp_path):
    """The same ramp with every servo obeying ends as 'end' (the threshold is not too tight)."""
    with VirtualChain(CAL.ids.tolist(), baud=1_000_000, positions=start_at(np.zeros(N))) as chain:
        rep, tel = run(chain, motion(ramp_motion()), tmp_path)
    assert rep.stop_reason == "end" and not rep.faults, rep.describe()


def test_a_watchdog_the_rate_cannot_feed_is_refused_before_anything_is_sent(tmp_path):
    with VirtualChain(CAL.ids.tolist(), baud=1_000_000, positions=start_at(np.zeros(N))) as chain:
        with pytest.raises(UserError, match="--watchdog-ms 100 is too short for --rate 5 Hz"):
            from motion2robot.hardware.stream import stream_motion
            stream_motion(motion(np.zeros((5, N))), LIMITS, __import__("tests.test_hardware_stream").test_hardware_stream.SMAP,
                          lambda: None, rate_hz=5.0, policy=TorquePolicy(watchdog_ms=100))
        assert chain.stats()["goal_writes"] == 0


def test_sub_tick_velocity_limit_holds_on_the_wire(tmp_path):
    """0.05 rad/s at 100 Hz is 0.33 ticks per tick: the servos move 0.05 rad/s, not one tick per tick."""
    slow = JointLimits(LIMITS.names, LIMITS.lower, LIMITS.upper, np.full(N, 0.05))
    q = np.minimum(np.arange(60)[:, None] / 10.0, 1.0) * np.ones(N)  # wants 5 rad/s, 100x the limit
    with VirtualChain(CAL.ids.tolist(), baud=1_000_000, positions=start_at(np.zeros(N))) as chain:
        names = dict(zip(CAL.ids.tolist(), CAL.joints))
        from motion2robot.hardware.dynamixel_bus import DynamixelBus
        from motion2robot.hardware.stream import stream_motion
        from tests.test_hardware_stream import LATENCY_MS, SMAP
        rep = stream_motion(motion(q), slow, SMAP,
                            lambda: DynamixelBus(chain.port_name, 1_000_000, names=names, latency_timer_ms=LATENCY_MS),
                            rate_hz=100.0, policy=TorquePolicy(on_end=0.0, ramp_speed=6.0), max_seconds=1.5,
                            telemetry_path=tmp_path / "t.jsonl")
        log = chain.wire_log()
    assert rep.stop_reason == "end", rep.describe()
    per = {}
    for t, sid, ticks in log:
        per.setdefault(sid, []).append((t, ticks))
    tick_rad = 1 / CAL.ticks_per_rad
    for sid, seq in per.items():
        t = np.array([a for a, _ in seq])
        g = np.array([b for _, b in seq], dtype=np.float64)
        n = len(g)
        assert n > 100
        for lag in (1, 10, 50, n - 1):
            moved = np.abs(g[lag:] - g[:-lag]).max() * tick_rad
            assert moved <= 0.05 * lag / 100.0 + tick_rad + 1e-9, (sid, lag, moved)
        assert abs(g[-1] - g[0]) * tick_rad >= 0.05 * (n - 1) / 100.0 - 2 * tick_rad  # and it did move at the limit
        assert t[-1] > t[0]


def _op3_motion(tmp_path: Path, seconds: float = 4.0) -> Path:
    from motion2robot.robot import load_robot

    robot = load_robot("op3")
    T = int(seconds * 50)
    qpos = np.tile(robot.nominal_qpos, (T, 1))
    qpos[:, 7:] += 0.2 * np.sin(np.arange(T) / 50.0 * 2 * np.pi)[:, None]
    return RobotMotion(qpos, 50.0, robot.joint_names, "op3").save(tmp_path / "m.npz")


def test_cli_low_rate_sets_the_watchdog_and_the_servos_keep_obeying(tmp_path, capsys):
    """Issue 20: '--virtual --rate 5 --duration 3' exited 0 with servos frozen from tick 6 on."""
    path = _op3_motion(tmp_path)
    tel_path = tmp_path / "t.jsonl"
    code = main(["stream", str(path), "--virtual", "--rate", "5", "--duration", "3", "--loop", "--ramp-speed", "4",
                 "--on-end", "off", "--latency-ms", "10", "--telemetry", str(tel_path)])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "Bus Watchdog set to 420 ms for 5 Hz" in err
    tel = read_telemetry(tel_path)
    assert tel.header["policy"]["watchdog_ms"] == 420 and tel.stop["reason"] == "end"
    play = [t for t in tel.ticks if t["phase"] == "play"]
    present = np.array([t["present"] for t in play])
    assert len(play) >= 10 and np.ptp(present, axis=0).max() > 0.1  # present moved: not frozen
    code = main(["stream", str(path), "--virtual", "--rate", "5", "--watchdog-ms", "100", "--telemetry", str(tel_path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--watchdog-ms 100 is too short for --rate 5 Hz" in err[0]


def test_a_watchdog_tripped_by_a_low_rate_is_a_named_fault(tmp_path, capsys, monkeypatch):
    """The issue's case as it ran then: '--rate 5' with the 100 ms Bus Watchdog printed 'stream: end'
    and exit 0 while the servos had stopped obeying from tick 6. The rate now sets the watchdog
    (test above) or refuses a short one; with that rule bypassed, the trip is still caught, named,
    and stops the stream with exit 2 and torque off."""
    from motion2robot.hardware import policy
    from motion2robot.hardware.watchdog import WatchdogSetting

    monkeypatch.setattr(policy, "watchdog_for_rate", lambda requested_ms, rate_hz: WatchdogSetting(100))
    tel_path = tmp_path / "t.jsonl"
    code = main(["stream", str(_op3_motion(tmp_path)), "--virtual", "--rate", "5", "--duration", "3", "--loop",
                 "--ramp-speed", "4", "--latency-ms", "10", "--telemetry", str(tel_path)])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("motion2robot: error: ")]
    assert code == 2 and len(err) == 1 and "stream fault (watchdog)" in err[0], err
    assert "longer than the Bus Watchdog (100 ms)" in err[0]
    tel = read_telemetry(tel_path)
    assert tel.header["policy"]["watchdog_ms"] == 100
    assert tel.stop["reason"] == "fault" and tel.stop["fault"] == "watchdog" and tel.stop["fault_tick"] <= 2
    assert len(tel.ticks) <= 3 and not any(tel.stop["torque"].values())


def test_a_stalled_servo_through_the_cli_is_a_named_fault_with_exit_2(tmp_path, capsys, monkeypatch):
    """Present diverging from the goal, as a user sees it: 'stream --virtual' on a chain whose
    servo 13 (r_knee) stops moving while it still answers ends in a 'divergence' fault, exit 2."""
    from motion2robot.robot import load_robot

    start = VirtualChain.__enter__

    def stalling(self):
        chain = start(self)
        chain.inject(Fault("stall", 13, after_writes=30))
        return chain

    monkeypatch.setattr(VirtualChain, "__enter__", stalling)
    robot = load_robot("op3")
    q = np.tile(robot.nominal_qpos, (200, 1))
    q[:, 7:] += 0.6 * np.sin(np.arange(200) / 50.0 * 2 * np.pi)[:, None]  # 0.6 rad at 1 Hz
    path = RobotMotion(q, 50.0, robot.joint_names, "op3").save(tmp_path / "m.npz")
    tel_path = tmp_path / "t.jsonl"
    code = main(["stream", str(path), "--virtual", "--ramp-speed", "4", "--latency-ms", "10", "--rest", "last",
                 "--telemetry", str(tel_path)])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("motion2robot: error: ")]
    assert code == 2 and len(err) == 1 and "stream fault (divergence): servo 13 (r_knee)" in err[0], err
    tel = read_telemetry(tel_path)
    assert tel.stop["reason"] == "fault" and tel.stop["fault"] == "divergence"
    assert not any(tel.stop["torque"].values())


def _stream_process(tmp_path: Path, *args: str) -> tuple[subprocess.Popen, Path]:
    path = _op3_motion(tmp_path)
    tel_path = tmp_path / "t.jsonl"
    proc = subprocess.Popen([sys.executable, "-m", "motion2robot", "stream", str(path), "--loop", "--ramp-speed", "4",
                             "--telemetry", str(tel_path), *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    return proc, tel_path


def _wait_ticks(proc: subprocess.Popen, tel_path: Path, n: int) -> None:
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            if len(read_telemetry(tel_path).ticks) >= n:
                return
        except InputFileError:  # not written yet, or the header line still on its way
            pass
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.02)
    raise AssertionError("the stream did not start")


def test_sigstop_longer_than_the_watchdog_is_a_fault(tmp_path):
    """Issue 20: a 0.5 s SIGSTOP at 100 Hz froze the servos for the rest of the run, exit 0."""
    proc, tel_path = _stream_process(tmp_path, "--virtual", "--baud", "1000000", "--latency-ms", "10")
    try:
        _wait_ticks(proc, tel_path, 50)
        proc.send_signal(signal.SIGSTOP)
        time.sleep(0.5)
        proc.send_signal(signal.SIGCONT)
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 2, (out, err)
    assert "stream fault (watchdog)" in err and "silent for" in err
    tel = read_telemetry(tel_path)
    assert tel.stop["reason"] == "fault" and tel.stop["fault"] == "watchdog"
    assert all(v is False for v in tel.stop["torque"].values())


@pytest.mark.parametrize("rate, sig, target", [
    ("0.001", signal.SIGTERM, ("--virtual", "--watchdog-ms", "0", "--latency-ms", "10")),  # the cases
    ("0.2", signal.SIGINT, ("--virtual", "--watchdog-ms", "0", "--latency-ms", "10")),
    ("0.05", signal.SIGINT, ("--dry-run",)),
], ids=["0.001 Hz SIGTERM virtual", "0.2 Hz SIGINT virtual", "0.05 Hz SIGINT dry run"])
def test_signals_act_within_100_ms_at_a_low_rate(tmp_path, rate, sig, target):
    """Issue 20: at --rate 0.2 SIGINT took 2.4 s, at --rate 0.001 SIGTERM was ignored for 15 min.
    The signal comes just after a tick, the next one 5 s to 1000 s away; the stream must stop (torque
    off on every servo, the stop line written) long before it: measured 15-35 ms, asserted < 2 s
    so that a loaded machine cannot fail it while a loop that waits for the tick always does."""
    proc, tel_path = _stream_process(tmp_path, *target, "--rate", rate)
    try:
        _wait_ticks(proc, tel_path, 1)
        time.sleep(0.2)
        t0 = time.monotonic()
        proc.send_signal(sig)
        while proc.poll() is None and time.monotonic() - t0 < 30:
            if read_telemetry(tel_path).stop is not None:
                break
            time.sleep(0.005)
        acted = time.monotonic() - t0
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, (out, err)
    assert acted < 2.0, acted
    tel = read_telemetry(tel_path)
    assert tel.stop["reason"] == "interrupt" and len(tel.ticks) <= 2  # no tick waited for
    if "--virtual" in target:
        assert len(tel.stop["torque"]) == N and not any(tel.stop["torque"].values())


def test_the_wait_for_a_tick_sleeps_in_short_slices_and_stops_when_interrupted(monkeypatch):
    """At 0.001 Hz the next tick is 1000 s away: the wait sleeps at most SLEEP_SLICE_S (20 ms) at a
    time, asks after every slice, and returns False at once when a signal came."""
    from motion2robot.hardware import timing

    slept: list[float] = []
    monkeypatch.setattr(timing.time, "sleep", slept.append)  # nothing really sleeps
    asked = []

    def interrupted() -> bool:
        asked.append(1)
        return len(slept) >= 5  # the signal came during the fifth slice

    assert timing.sleep_until(timing.clock() + 1000.0, interrupted=interrupted) is False
    assert len(slept) == 5 and max(slept) <= timing.SLEEP_SLICE_S <= 0.05 and len(asked) == 6

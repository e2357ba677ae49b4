"""Hardware building blocks without I/O: Protocol 2.0 framing, control table, calibration, guard, policy."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from motion2robot.errors import InputFileError, RobotConfigError
from motion2robot.hardware import protocol as P
from motion2robot.hardware.calibration import (
    Calibration,
    load_calibration,
    record_zero_offsets,
    save_calibration,
)
from motion2robot.hardware.control_table import control_table, describe_hardware_error
from motion2robot.hardware.errors import SafetyError
from motion2robot.hardware.guard import SafetyGuard
from motion2robot.hardware.limits import JointLimits
from motion2robot.hardware.policy import TorquePolicy
from motion2robot.robot.servo_map import ServoMap, ServoSpec


def test_crc_known_vector_and_packet_layout():
    assert P.packet(1, P.PING) == bytes.fromhex("FFFFFD0001030001194E")
    st_ = P.status_packet(3, 0x80, b"\x01\x02")
    assert st_[:8] == bytes.fromhex("FFFFFD0003060055") and st_[8] == 0x80
    assert P.crc16(st_[:-2]) == st_[-2] | st_[-1] << 8


@given(st.binary(max_size=64))
def test_stuffing_round_trip_and_no_header_inside(payload):
    s = P.stuff(payload)
    assert P.unstuff(s) == payload
    # after stuffing, a header pattern is always followed by the stuffing byte
    for k in range(len(s) - 2):
        if s[k:k + 3] == b"\xff\xff\xfd":
            assert k + 3 < len(s) and s[k + 3] == 0xFD


@given(st.integers(0, 252), st.integers(0, 255), st.binary(max_size=40), st.binary(max_size=8),
       st.integers(1, 7))
def test_reader_finds_packets_after_garbage_and_in_pieces(sid, inst, params, garbage, pieces):
    pkt = P.packet(sid, inst, params)
    stream = garbage.replace(b"\xff", b"") + pkt + pkt
    r = P.PacketReader()
    got = []
    cut = max(1, len(stream) // pieces)
    for k in range(0, len(stream), cut):
        got += r.feed(stream[k:k + cut], float(k))
    assert [(p.id, p.instruction, p.params, p.crc_ok) for p in got] == [(sid, inst, params, True)] * 2


def test_reader_flags_corrupt_crc():
    pkt = bytearray(P.packet(5, P.READ, b"\x84\x00\x04\x00"))
    pkt[-1] ^= 0xFF
    (p,) = P.PacketReader().feed(bytes(pkt), 0.0)
    assert not p.crc_ok


def test_control_table_signed_values_and_rules():
    t = control_table("XM430-W350")
    pos = t["present_position"]
    assert (pos.address, pos.size, pos.signed) == (132, 4, True)
    assert pos.decode(pos.encode(-5)) == -5 and pos.encode(-1) == b"\xff\xff\xff\xff"
    assert t["torque_enable"].address == 64 and t["hardware_error_status"].address == 70
    assert t["bus_watchdog"].address == 98 and t.model_number == 1020
    assert t["id"].address < t.eeprom_end <= t["torque_enable"].address
    assert describe_hardware_error(0x20) == "overload" and describe_hardware_error(0) == "none"
    with pytest.raises(RobotConfigError, match="control table"):
        control_table("AX-12")


def _servo_map(n=4, sign=None, offset=None):
    sign = sign or [1] * n
    offset = offset or [0] * n
    return ServoMap("XM430-W350", 1_000_000, 4096, 2048,
                    tuple(ServoSpec(f"j{i}", i + 1, sign[i], offset[i]) for i in range(n)))


@given(arrays(np.float64, 4, elements=st.floats(-3.0, 3.0)), st.lists(st.sampled_from([1, -1]), min_size=4, max_size=4),
       st.lists(st.integers(-500, 500), min_size=4, max_size=4))
def test_calibration_round_trip_within_one_tick(q, sign, offset):
    cal = Calibration.from_servo_map(_servo_map(sign=sign, offset=offset))
    ticks = cal.to_ticks(q)
    back = cal.to_radians(ticks)
    assert np.all(np.abs(back - q) <= 0.5 / cal.ticks_per_rad + 1e-12)
    assert np.array_equal(cal.to_ticks(back), ticks)  # ticks -> rad -> ticks is exact


def test_calibration_zero_offsets_file(tmp_path):
    sm = _servo_map(sign=[1, -1, 1, -1])
    nominal = {"j0": 0.5, "j1": -0.3, "j2": 0.0, "j3": 1.0}
    cal0 = Calibration.from_servo_map(sm)
    true_offsets = np.array([10, -25, 3, 0])
    present = cal0.to_ticks(np.array(list(nominal.values()))) + true_offsets
    offsets = record_zero_offsets(sm, dict(zip(cal0.ids.tolist(), present.tolist())), nominal)
    assert list(offsets.values()) == true_offsets.tolist()
    path = save_calibration(tmp_path / "c.json", "toy", offsets)
    cal = Calibration.from_servo_map(sm, load_calibration(path))
    assert np.allclose(cal.to_radians(present), list(nominal.values()), atol=0.5 / cal.ticks_per_rad)
    (tmp_path / "bad.json").write_text("{}")
    with pytest.raises(InputFileError, match="not a motion2robot calibration"):
        load_calibration(tmp_path / "bad.json")


LIM = JointLimits(("j0", "j1", "j2", "j3"), [-1.0, -2.0, 0.0, -0.5], [1.0, 0.5, 2.0, 0.5], [2.0, 4.0, 1.0, 6.0])


@settings(max_examples=200)
@given(arrays(np.float64, (25, 4), elements=st.one_of(st.floats(-8, 8), st.just(math.nan), st.just(math.inf),
                                                      st.just(math.pi), st.just(-math.pi))),
       st.lists(st.sampled_from([1, -1]), min_size=4, max_size=4), st.booleans())
def test_guard_goals_stay_within_limits_and_step(targets, sign, ramp):
    cal = Calibration.from_servo_map(_servo_map(sign=sign, offset=[0, 7, -3, 100]))
    rate = 100.0
    g = SafetyGuard(LIM, cal, rate, ramp_speed=0.5)
    last = g.start(cal.to_ticks(np.zeros(4) + [0.0, 0.0, 1.0, 0.0]))
    speed = (np.minimum(0.5, LIM.velocity) if ramp else LIM.velocity) * cal.ticks_per_rad / rate  # ticks per tick
    for t in targets:
        goal = g.next_goal(t, ramp)
        q = cal.to_radians(goal)
        assert np.all(q >= LIM.lower - 1e-12) and np.all(q <= LIM.upper + 1e-12)
        assert np.all(np.abs(goal - last) <= speed + 1.0)  # one tick of quantisation at most
        held = ~np.isfinite(t)
        assert np.array_equal(goal[held], last[held])
        last = goal


def test_guard_refuses_pose_out_of_limits_and_unreadable():
    cal = Calibration.from_servo_map(_servo_map())
    g = SafetyGuard(LIM, cal, 100.0)
    with pytest.raises(SafetyError, match=r"servo 3 \(j2\).*outside its limits"):
        g.start(cal.to_ticks(np.array([0.0, 0.0, -0.5, 0.0])))
    with pytest.raises(SafetyError, match="could not be read"):
        g.start(np.array([2048.0, np.nan, 2048.0, 2048.0]))


def test_torque_policy_parsing(tmp_path):
    p = TorquePolicy.parse("on_end=hold:2,on_fault=off,watchdog_ms=90")
    assert (p.on_end, p.on_fault, p.watchdog_units) == (2.0, 0.0, 5)
    f = tmp_path / "p.toml"
    f.write_text('on_interrupt = "hold:1.5"\nramp_out = false\n')
    q = TorquePolicy.parse(str(f))
    assert q.on_interrupt == 1.5 and q.ramp_out is False
    with pytest.raises(Exception, match="unknown keys"):
        TorquePolicy.parse("on_start=off")

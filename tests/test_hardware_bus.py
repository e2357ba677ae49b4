"""DynamixelBus (the real dynamixel-sdk) against the virtual Protocol 2.0 chain on a pty."""

from __future__ import annotations

import time

import pytest

from motion2robot.hardware.dynamixel_bus import DynamixelBus, LowLatencyPortHandler
from motion2robot.hardware.errors import CommError, PortError, ServoStatusError
from motion2robot.hardware.virtual_chain import Fault, VirtualChain

IDS = [1, 2, 3, 4]
LATENCY_MS = 10.0  # generous: the pty relay stalls for several ms on a loaded shared machine


@pytest.fixture()
def chain():
    with VirtualChain(IDS, baud=1_000_000, positions={3: 1000}) as c:
        yield c


@pytest.fixture()
def bus(chain):
    with DynamixelBus(chain.port_name, 1_000_000, names={3: "r_sho_roll"}, latency_timer_ms=LATENCY_MS) as b:
        yield b


def test_scan_lists_model_firmware_and_error_status(bus, chain):
    found = bus.scan()  # broadcast ping
    assert [s.id for s in found] == IDS
    assert {(s.model, s.model_number, s.firmware, s.hardware_error_status) for s in found} == {("XM430-W350", 1020, 48, 0)}
    chain.inject(Fault("alert", 2))
    by_id = {s.id: s for s in bus.scan([1, 2, 9])}
    assert sorted(by_id) == [1, 2] and by_id[2].hardware_error_status == 0x20


def test_read_write_signed_and_stuffed_values(bus):
    bus.write(2, "homing_offset", -1234)
    assert bus.read(2, "homing_offset") == -1234
    bus.write(2, "operating_mode", 4)  # extended position: negative goals allowed
    v = -131073  # bytes FF FF FD FF: the instruction and the status packet both need byte stuffing
    bus.write(2, "goal_position", v)
    assert bus.read(2, "goal_position") == v
    assert bus.read(3, "present_position") == 1000


def test_eeprom_write_with_torque_on_is_refused_naming_the_servo(bus):
    bus.write(3, "torque_enable", 1)
    with pytest.raises(ServoStatusError, match=r"servo 3 \(r_sho_roll\).*access error"):
        bus.write(3, "return_delay_time", 0)
    with pytest.raises(ServoStatusError, match="data range"):
        bus.write(3, "goal_position", 5000)  # beyond Max Position Limit in position mode
    bus.write(3, "torque_enable", 0)
    bus.write(3, "return_delay_time", 0)


def test_fast_and_plain_sync_read_agree_and_goals_move_servos(bus):
    bus.scan(IDS)
    assert bus.uses_fast_sync_read(IDS)
    bus.set_torque(IDS, True)
    bus.sync_write("goal_position", {1: 2100, 2: 2000, 3: 1000, 4: 2048})
    time.sleep(0.1)
    fast = bus.sync_read("present_position", IDS)
    bus.fast_sync_read = False
    plain = bus.sync_read("present_position", IDS)
    assert fast.values == plain.values == {1: 2100, 2: 2000, 3: 1000, 4: 2048}
    assert fast.alerts() == plain.alerts() == []


@pytest.mark.parametrize("fast", [True, False])
def test_faults_name_the_servo(bus, chain, fast):
    bus.fast_sync_read = fast
    chain.inject(Fault("vanish", 3))
    with pytest.raises(CommError, match=r"servo 3 \(r_sho_roll\).*no status packet"):
        bus.sync_read("present_position", IDS)
    chain.inject(Fault("corrupt_crc", 2))
    with pytest.raises(CommError, match=r"servo 2.*Incorrect status packet"):
        bus.sync_read("present_position", [1, 2, 4])


def test_one_lost_reply_is_recovered_and_reported(bus, chain):
    chain.inject(Fault("drop_replies", 4, count=1))
    assert bus.read(4, "present_position") == 2048
    assert any("needed 2 tries" in m for m in bus.recoveries())


def test_alert_reboot_and_bus_watchdog(bus, chain):
    chain.inject(Fault("alert", 1))
    r = bus.sync_read("present_position", IDS)
    assert r.alerts() == [1] and bus.read(1, "hardware_error_status") == 0x20
    with pytest.raises(ServoStatusError, match="servo 1"):
        bus.write(1, "torque_enable", 1)  # shutdown: only reboot restores torque
    bus.reboot(1)
    assert bus.read(1, "hardware_error_status") == 0
    # Bus Watchdog: a silent bus stops the servo and refuses goals until reset
    bus.write(1, "torque_enable", 1)
    bus.write(1, "bus_watchdog", 2)  # 40 ms
    bus.write(1, "goal_position", 4000)
    time.sleep(0.15)
    snap = chain.snapshot()[1]
    assert snap["bus_watchdog"] == 0xFF and snap["present"] < 4000
    with pytest.raises(ServoStatusError, match="data range"):
        bus.write(1, "goal_position", 2048)
    bus.write(1, "bus_watchdog", 0)
    bus.write(1, "goal_position", 2048)


def test_port_closing_mid_stream_is_a_port_error(bus, chain):
    chain.inject(Fault("close_port"))
    with pytest.raises(PortError, match="failed while"):
        bus.sync_read("present_position", IDS)
    assert not bus.is_open


def test_latency_timer_replaces_the_sdk_constant():
    p = LowLatencyPortHandler("/dev/null", latency_timer_ms=1.0)
    p.tx_time_per_byte = 0.01  # 1 Mbps
    p.setPacketTimeout(15)
    assert p.packet_timeout == pytest.approx(0.15 + 2 * 1.0 + 2.0)  # SDK: 0.15 + 2 * 16 + 2


def test_open_missing_port_is_a_port_error():
    with pytest.raises(PortError, match="cannot open /nonexistent/tty"):
        DynamixelBus("/nonexistent/tty", 1_000_000).open()


@pytest.mark.parametrize("rdt", [0, 250])
def test_wire_time_and_return_delay_time_are_modelled(rdt):
    """The chain's bus model (arithmetic, not wall clock): a plain sync read of 4 servos occupies
    ((14 + 4) + 4 * 15 bytes) * 10 bits / baud plus 4 Return Delay Times."""
    with VirtualChain(IDS, baud=1_000_000, wire_time=True, return_delay_time=rdt) as chain, \
            DynamixelBus(chain.port_name, 1_000_000, latency_timer_ms=LATENCY_MS, fast_sync_read=False) as bus:
        before = chain.stats()["bus_time_s"]
        bus.sync_read("present_position", IDS)
        spent = chain.stats()["bus_time_s"] - before
        assert bus.read(1, "return_delay_time") == rdt
    assert spent == pytest.approx((18 + 4 * 15) * 10 / 1e6 + 4 * rdt * 2e-6, abs=1e-9)

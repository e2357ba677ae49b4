"""The servos and stream commands through the real CLI entry point (virtual chain, no hardware)."""

from __future__ import annotations

import json

import numpy as np

from motion2robot.cli import main
from motion2robot.hardware.telemetry import read_telemetry
from motion2robot.robot_motion import RobotMotion

LAT = ["--latency-ms", "10"]  # generous: the pty relay stalls for several ms on a loaded shared machine


def test_servos_scan_virtual_lists_every_op3_servo(capsys):
    assert main(["servos", "scan", "--virtual", "--baud", "1000000", *LAT]) == 0
    out = capsys.readouterr().out
    assert "20 servo(s) on virtual chain at 1000000 baud" in out
    assert "  7  r_hip_yaw    XM430-W350    48  ok" in out


def test_servos_calibrate_virtual_writes_offsets(tmp_path, capsys):
    out_file = tmp_path / "op3.calib.json"
    assert main(["servos", "calibrate", "--virtual", "-o", str(out_file), *LAT]) == 0
    doc = json.loads(out_file.read_text())
    assert doc["robot"] == "op3" and len(doc["offsets"]) == 20
    assert all(v == 0 for v in doc["offsets"].values())  # the virtual robot stands exactly in its nominal posture


def test_servos_write_out_of_range_value_is_refused_naming_the_servo(capsys):
    code = main(["servos", "write", "--virtual", "--register", "led", "--value", "7", "--ids", "2", *LAT])
    err = capsys.readouterr().err
    assert code == 2 and "servo 2 (l_sho_pitch)" in err and "data range" in err


def test_stream_dry_run_through_the_cli(tmp_path, capsys):
    from motion2robot.robot import load_robot

    robot = load_robot("op3")
    qpos = np.tile(robot.nominal_qpos, (20, 1))
    path = RobotMotion(qpos, 50.0, robot.joint_names, "op3").save(tmp_path / "m.npz")
    assert main(["stream", str(path), "--dry-run", "--on-end", "off"]) == 0
    out = capsys.readouterr().out
    assert "stream: end (dry run)" in out and "loop:" in out
    tel = read_telemetry(tmp_path / "m.telemetry.jsonl")
    assert tel.stop["reason"] == "end" and tel.header["dry_run"] is True


def test_stream_without_a_target_is_a_user_error(tmp_path, capsys):
    from motion2robot.robot import load_robot

    robot = load_robot("op3")
    path = RobotMotion(np.tile(robot.nominal_qpos, (5, 1)), 50.0, robot.joint_names, "op3").save(tmp_path / "m.npz")
    assert main(["stream", str(path)]) == 2
    assert "--virtual, --port DEV, or --dry-run" in capsys.readouterr().err

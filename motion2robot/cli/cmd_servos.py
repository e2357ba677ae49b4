"""``motion2robot servos``: scan the bus, record calibration offsets, reboot, torque off.

    motion2robot servos scan --virtual | --port /dev/ttyUSB0 --baud 2000000 [--ids 1-20]
    motion2robot servos calibrate --port /dev/ttyUSB0 -o op3.calib.json [--robot op3]
    motion2robot servos reboot --port /dev/ttyUSB0 --id 7
    motion2robot servos off --port /dev/ttyUSB0
    motion2robot servos write --port /dev/ttyUSB0 --register return_delay_time --value 0 [--ids 1-20]
"""

from __future__ import annotations

import argparse

from motion2robot.cli.numbers import SERVO_ID, number
from motion2robot.errors import UserError
from motion2robot.hardware.calibration import (
    Calibration,
    record_zero_offsets,
    save_calibration,
)
from motion2robot.hardware.connect import (
    add_bus_options,
    open_bus_factory,
    target_from_args,
)
from motion2robot.hardware.control_table import describe_hardware_error


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("servos", help="scan the servo bus, calibrate zero offsets, reboot, torque off",
                              description="Talk to the Dynamixel servos of a robot (or a virtual chain).")
    sub = p.add_subparsers(dest="servos_command", metavar="{scan,calibrate,reboot,off,write}", required=True)
    scan = sub.add_parser("scan", help="list servos: ID, model, firmware, hardware error status")
    scan.add_argument("--ids", help="IDs to ping, e.g. 1-20 or 1,3,5 (default: broadcast ping)")
    cal = sub.add_parser("calibrate", help="record zero offsets from the robot held in its nominal posture",
                         description="Hold the robot in its nominal posture (torque off), then run this: the present "
                                     "positions become the zero offsets written to the calibration file.")
    cal.add_argument("-o", "--output", required=True, help="calibration file to write (JSON)")
    reboot = sub.add_parser("reboot", help="reboot a servo (clears a hardware error shutdown)")
    reboot.add_argument("--id", type=SERVO_ID, required=True, dest="servo_id", help="servo ID, 0..252")
    off = sub.add_parser("off", help="torque off on every servo of the robot")
    wr = sub.add_parser("write", help="write one control-table register (by name) on servos, e.g. return_delay_time 0",
                        description="EEPROM registers (ID, baud, return delay time, limits...) need torque off.")
    wr.add_argument("--register", required=True, help="register name, e.g. return_delay_time")
    wr.add_argument("--value", type=number("register units", -(2**31), 2**32 - 1, whole=True), required=True,
                    help="raw value in the register's unit")
    wr.add_argument("--ids", help="IDs, e.g. 1-20 (default: every servo of the robot)")
    for sp, fn in ((scan, _scan), (cal, _calibrate), (reboot, _reboot), (off, _off), (wr, _write)):
        add_bus_options(sp)
        sp.add_argument("--robot", default="op3", help="robot whose servo map to use (default op3)")
        sp.set_defaults(func=fn)


def _servo_map(name: str):
    from motion2robot.robot import load_robot

    robot = load_robot(name)
    if robot.config.servos is None:
        raise UserError(f"robot '{name}' has no [servos] section in its config")
    return robot, robot.config.servos


def _parse_ids(text: str) -> list[int]:
    out: list[int] = []
    try:
        for part in text.split(","):
            a, _, b = part.partition("-")
            out += list(range(int(a), int(b or a) + 1))
    except ValueError:
        raise UserError(f"--ids: '{text}' is not like 1-20 or 1,3,5") from None
    if not out or not all(0 <= i <= 252 for i in out):
        raise UserError(f"--ids: '{text}' must name servo IDs in 0..252, like 1-20 or 1,3,5")
    return out


def _scan(args: argparse.Namespace) -> int:
    _, sm = _servo_map(args.robot)
    target = target_from_args(args, sm)
    names = {s.id: s.joint for s in sm.servos}
    ids = _parse_ids(args.ids) if args.ids else None
    with open_bus_factory(target, sm) as factory, factory() as bus:
        found = bus.scan(ids)
    print(f"{len(found)} servo(s) on {target.describe()}")
    print(f"{'ID':>3}  {'JOINT':<12} {'MODEL':<12} {'FW':>3}  ERROR STATUS")
    for s in found:
        hes = s.hardware_error_status or 0
        print(f"{s.id:>3}  {names.get(s.id, '-'):<12} {s.model:<12} {s.firmware:>3}  "
              f"{'ok' if not hes else f'0x{hes:02X} ' + describe_hardware_error(hes)}")
    missing = sorted((set(names) & set(ids or names)) - {s.id for s in found})
    if missing:
        print(f"missing from the {args.robot} servo map: {', '.join(f'{i} ({names[i]})' for i in missing)}")
    return 0 if found and not missing else 2


def _calibrate(args: argparse.Namespace) -> int:
    from motion2robot.util.output import output_path

    robot, sm = _servo_map(args.robot)
    output_path(args.output, "calibration file", ".json")
    target = target_from_args(args, sm)
    hinge = {n: i for i, n in enumerate(robot.joint_names)}
    nominal = {s.joint: float(robot.nominal_qpos[7 + hinge[s.joint]]) for s in sm.servos if s.joint in hinge}
    cal = Calibration.from_servo_map(sm)
    # a virtual chain starts in the nominal posture, as a robot held there would be
    positions = dict(zip(cal.ids.tolist(), cal.to_ticks([nominal.get(j, 0.0) for j in cal.joints]).tolist()))
    with open_bus_factory(target, sm, positions=positions) as factory, factory() as bus:
        present = bus.sync_read("present_position", cal.ids.tolist()).values
    offsets = record_zero_offsets(sm, present, nominal)
    path = save_calibration(args.output, args.robot, offsets)
    worst = max(offsets.items(), key=lambda kv: abs(kv[1]))
    print(f"wrote {path}: zero offsets of {len(offsets)} joints (largest {worst[0]} {worst[1]:+d} ticks)")
    return 0


def _reboot(args: argparse.Namespace) -> int:
    _, sm = _servo_map(args.robot)
    with open_bus_factory(target_from_args(args, sm), sm) as factory, factory() as bus:
        bus.reboot(args.servo_id)
    print(f"servo {args.servo_id} rebooted (torque is off)")
    return 0


def _off(args: argparse.Namespace) -> int:
    _, sm = _servo_map(args.robot)
    with open_bus_factory(target_from_args(args, sm), sm) as factory, factory() as bus:
        result = bus.set_torque([s.id for s in sm.servos], False)
    failed = {i: e for i, e in result.items() if e}
    for e in failed.values():
        print(f"motion2robot: error: {e}")
    print(f"torque off on {len(result) - len(failed)} of {len(result)} servos")
    return 2 if failed else 0


def _write(args: argparse.Namespace) -> int:
    _, sm = _servo_map(args.robot)
    ids = _parse_ids(args.ids) if args.ids else [s.id for s in sm.servos]
    with open_bus_factory(target_from_args(args, sm), sm) as factory, factory() as bus:
        for i in ids:
            bus.write(i, args.register, args.value)
        back = {i: bus.read(i, args.register) for i in ids}
    print(f"{args.register} = {args.value} on servos {', '.join(str(i) for i in ids)} "
          f"(read back: {sorted(set(back.values()))})")
    return 0

"""``motion2robot check FILE``: is a motion feasible on the robot? Verdict table, reasons, JSON report.

FILE is a RobotMotion ``.npz`` (from ``motion2robot retarget``) or any human motion file the
readers accept, which is retargeted first. Exit code 0 feasible, 1 infeasible, 2 error.
"""

from __future__ import annotations

import argparse

from motion2robot.cli.check_options import add_check_options, check_option_kwargs
from motion2robot.cli.motion_input import load_motion_input
from motion2robot.cli.read_options import add_read_options
from motion2robot.cli.retarget_options import add_retarget_options


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "check", help="check a robot motion's feasibility in MuJoCo (limits, collisions, balance, torques, playback)",
        description="Judge a robot motion (.npz from 'motion2robot retarget') or a human motion file "
                    "(retargeted first) on the robot: joint, speed, acceleration and torque limits, "
                    "self-collision, floor, balance (CoM/ZMP), physics playback with servo-like "
                    "actuators, and the root path against the human's. Exit code 0 feasible, "
                    "1 infeasible, 2 error.")
    p.add_argument("file", help="robot motion .npz, or a human motion file (retargeted first)")
    p.add_argument("--robot", help="robot name or config path (default: the motion's own robot; op3 for human motion)")
    p.add_argument("--json", metavar="REPORT.json", help="write the FeasibilityReport as JSON")
    p.add_argument("--html", metavar="REPORT.html",
                   help="write a self-contained HTML report (verdict, reasons, plots, key frames)")
    p.add_argument("--no-physics", dest="physics", action="store_false", help="skip the physics playback")
    p.add_argument("--clip", type=int, help="clip index of a multi-clip human motion file")
    add_retarget_options(p)
    add_check_options(p)
    add_read_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from motion2robot.validate import CheckOptions, check, verdict_table

    from motion2robot.util.output import output_path

    for out, what, suffix in ((args.json, "JSON report", ".json"), (args.html, "HTML report", ".html")):
        if out:
            output_path(out, what, suffix)  # before the work: a directory here is a user error
    motion, robot, human = load_motion_input(args.file, args)
    report = check(motion, robot, CheckOptions(physics=args.physics, **check_option_kwargs(args)))
    print(verdict_table(report))
    if args.json:
        print(f"report written to {report.to_json(args.json)}")
    if args.html:
        from motion2robot.viz.html_report import write_html_report

        print(f"HTML report written to {write_html_report(report, motion, robot, args.html, human=human)}")
    return 0 if report.feasible else 1

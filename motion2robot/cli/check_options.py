"""The check thresholds on the command line (``check`` and ``batch``), as CheckOptions fields."""

from __future__ import annotations

import argparse
from typing import Any

from motion2robot.cli.numbers import RATE_HZ, number

#: (flag, CheckOptions field, type, help) of every threshold the command line sets.
_FLAGS = (
    ("--slip-speed", "slip_speed", number("m/s", 0.0, 10.0, low_open=True),
     "m/s a planted sole point (or a swing foot near the floor) may move horizontally (default 0.01)"),
    ("--touch-height", "touch_height", number("m", 0.0, 0.1, low_open=True), "m below which a sole point touches the floor (default 0.002)"),
    ("--swing-clearance", "swing_clearance", number("m", 0.0, 1.0, low_open=True),
     "m a moving swing foot keeps above the floor (default: 2%% of the robot's standing root height, 5 mm on the OP3)"),
    ("--stream-rate", "stream_rate", RATE_HZ,
     "Hz of the playback's servo goals, as 'stream --rate' would send them (default 100)"),
)


def add_check_options(p: argparse.ArgumentParser) -> None:
    """Add the threshold flags and ``--sag-compensation`` to a subcommand's parser."""
    g = p.add_argument_group("check thresholds")
    for flag, dest, kind, text in _FLAGS:
        g.add_argument(flag, dest=f"check_{dest}", type=kind, metavar="X", help=text)
    g.add_argument("--sag-compensation", dest="check_sag_compensation", action="store_true", default=None,
                   help="the playback's servo goals add the predicted servo sag (tau/kp), as "
                        "'stream --sag-compensation' does")


def check_option_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """The CheckOptions fields the user set (flags left out are not in the dict)."""
    names = [dest for _, dest, _, _ in _FLAGS] + ["sag_compensation"]
    return {n: getattr(args, f"check_{n}") for n in names if getattr(args, f"check_{n}", None) is not None}

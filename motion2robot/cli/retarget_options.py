"""The retargeting options shared by the commands that retarget (retarget, check, sim, batch):
tempo policy, tempo cap, legs policy, balance. Values are checked when they are parsed."""

from __future__ import annotations

import argparse
from dataclasses import replace

from motion2robot.errors import UserError


def _tempo(value: str):
    from motion2robot.retarget.tempo import parse_tempo

    try:
        return parse_tempo(value)
    except UserError as err:
        raise argparse.ArgumentTypeError(str(err).split(": ", 1)[-1]) from None


def _cap(value: str) -> float:
    from motion2robot.retarget.tempo import parse_cap

    try:
        return parse_cap(value)
    except UserError as err:
        raise argparse.ArgumentTypeError(str(err).split(": ", 1)[-1]) from None


def add_retarget_options(p: argparse.ArgumentParser) -> None:
    """--tempo, --tempo-cap, --legs, --no-balance."""
    from motion2robot.retarget.options import LEGS

    p.add_argument("--tempo", type=_tempo, default="auto", metavar="human|similar|auto|K",
                   help="timing of the robot motion: 'human' keeps the generated timing, 'similar' plays it "
                        "dynamically similar for the robot's size (durations x sqrt(leg scale)), 'auto' (default) "
                        "the smallest slow-down that passes the checks, or a factor K (2 = twice as slow)")
    p.add_argument("--tempo-cap", type=_cap, default=None, metavar="K",
                   help="the slowest tempo 'auto' may choose (default 2.5)")
    p.add_argument("--legs", choices=list(LEGS), default="auto",
                   help="'whole' body, 'steps' (the legs walk the human's footsteps as a walking pattern, steps "
                        "shortened to what the robot reaches, torso upright), 'stance' (the legs hold a stance while "
                        "the upper body and head perform), or 'auto' (default: the first of whole, steps, stance "
                        "that passes the checks; always reported)")
    p.add_argument("--no-balance", dest="balance", action="store_false",
                   help="do not keep the CoM/ZMP over the support polygon (running, jumping)")


def retarget_options_from(args: argparse.Namespace, base=None):
    """RetargetOptions from the parsed arguments (over ``base``)."""
    from motion2robot.retarget import RetargetOptions

    opts = base or RetargetOptions()
    changes = {"tempo": getattr(args, "tempo", "auto"), "legs": getattr(args, "legs", "auto"),
               "balance": getattr(args, "balance", True)}
    if getattr(args, "tempo_cap", None) is not None:
        changes["tempo_cap"] = args.tempo_cap
    return replace(opts, **changes)


def tempo_line(motion) -> str:
    """One line: the tempo chosen, why, and the alternative taken (if any)."""
    m = motion.meta
    if "tempo" not in m:
        return ""
    s = f"tempo x{float(m['tempo']):.2f}: {m.get('tempo_reason', '')}"
    fb = m.get("fallback")
    if fb:
        s += f"; legs: {fb['mode']} ({fb['why']})"
    return s

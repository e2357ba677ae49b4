"""The reader options shared by every command that reads human motion (inspect, retarget, check,
sim, batch): format override, source frame rate, normalisation statistics, units, up axis, name
map, ASF skeleton."""

from __future__ import annotations

import argparse

from motion2robot.cli.numbers import FPS


def add_read_options(p: argparse.ArgumentParser) -> None:
    """The reader options shared by every command that reads human motion."""
    from motion2robot.motion.formats import FORMATS, format_help, formats_using

    def used_by(option: str) -> str:
        return f" (formats: {', '.join(formats_using(option))})"

    p.add_argument("--format", choices=FORMATS, metavar="NAME", help=format_help())
    p.add_argument("--source-fps", dest="fps", type=FPS, metavar="FPS",
                   help="override the frame rate the file declares (e.g. 20 for IK-made BVH files that say 24)")
    p.add_argument("--mean", help="Mean.npy for normalised features" + used_by("mean"))
    p.add_argument("--std", help="Std.npy for normalised features" + used_by("std"))
    p.add_argument("--stats", metavar="STATS",
                   help="statistics file (pickled mean/std dict) of normalised features" + used_by("stats"))
    p.add_argument("--body-model", dest="body_model", metavar="PATH",
                   help="your SMPL-H/SMPL/SMPL-X model file (.npz, or .pkl of plain arrays): joints of SMPL "
                        "parameters from its rest joints and tree" + used_by("body_model"))
    p.add_argument("--strict", action="store_true", default=None,
                   help="refuse SMPL parameters without --body-model instead of using the approximate skeleton")
    p.add_argument("--trajectory", metavar="FILE",
                   help="root path the motion was asked to follow: (T,2) or (T,3) .npy/.csv/.txt in the motion "
                        "file's axes and units; the robot's error against it is reported (OmniControl results "
                        "carry theirs as 'hint')")
    p.add_argument("--units", choices=["m", "cm", "mm", "inch", "cmu"], help="override unit detection")
    p.add_argument("--up", choices=["x", "y", "z", "-x", "-y", "-z"], help="override up-axis detection")
    p.add_argument("--name-map", dest="name_map",
                   help="TOML map of joint names to SMPL22 keypoints" + used_by("name_map"))
    p.add_argument("--skeleton", metavar="FILE.asf",
                   help="ASF skeleton of an .amc motion (default: the .asf beside it, e.g. 01.asf for 01_01.amc)"
                        + used_by("skeleton"))


def read_args_kwargs(args: argparse.Namespace) -> dict:
    return {k: getattr(args, k, None) for k in ("format", "fps", "mean", "std", "units", "up", "name_map", "skeleton",
                                          "stats", "body_model", "strict", "trajectory")}

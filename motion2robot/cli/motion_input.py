"""The input of commands that take "a robot motion .npz or a human motion file" (check, sim):
a RobotMotion is used as is; human motion is read and retargeted first."""

from __future__ import annotations

import argparse
import zipfile
from pathlib import Path

import numpy as np

from motion2robot.cli.read_options import read_args_kwargs
from motion2robot.errors import InputFileError, UserError
from motion2robot.robot_motion import NPZ_KEYS


def is_robot_motion(path: Path) -> bool:
    """True for an .npz holding the RobotMotion keys."""
    if path.suffix.lower() != ".npz" or not path.is_file():
        return False
    try:
        with np.load(path, allow_pickle=False) as z:
            return all(k in z.files for k in NPZ_KEYS)
    except (OSError, ValueError, zipfile.BadZipFile):
        return False


def load_motion_input(path: str | Path, args: argparse.Namespace):
    """(robot motion, robot, human motion or None) for ``path``.

    A RobotMotion .npz is loaded with ``args.robot`` or its own robot (whose joints must match);
    anything else is read as human motion (``args.clip`` selects a clip of a multi-clip file,
    the reader options come from ``args``) and retargeted onto ``args.robot`` (default op3)."""
    from motion2robot.robot import load_robot
    from motion2robot.robot_motion import RobotMotion

    path = Path(path)
    if is_robot_motion(path):
        motion = RobotMotion.load(path)
        robot = load_robot(args.robot or motion.robot)
        if tuple(robot.joint_names) != tuple(motion.joint_names):
            raise UserError(f"{path}: made for robot {motion.robot!r}, whose joints differ from {robot.name!r}'s; "
                            f"drop --robot or retarget the motion for {robot.name}")
        return motion, robot, None
    from motion2robot.motion import read_motion
    from motion2robot.retarget import retarget

    clips = read_motion(path, clip=getattr(args, "clip", None), **read_args_kwargs(args))
    if not clips:
        raise InputFileError(f"{path}: no motion clip found; check the file")
    if len(clips) > 1:
        raise UserError(f"{path}: holds {len(clips)} clips; choose one with --clip 0..{len(clips) - 1}")
    from motion2robot.cli.retarget_options import retarget_options_from
    from motion2robot.retarget.control_path import with_control_path

    robot = load_robot(args.robot or "op3")
    return with_control_path(retarget(clips[0], robot, retarget_options_from(args)), clips[0]), robot, clips[0]

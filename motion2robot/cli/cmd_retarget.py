"""``motion2robot retarget INPUT``: human motion -> robot motion ``.npz`` (casadi IK over all frames).

Writes ``OUT.npz`` with exactly the keys qpos, fps, joint_names, robot, meta; with ``--clip all``
on a multi-clip input, one ``OUT_clipN.npz`` per clip. Prints one summary line per clip and the
tempo/legs chosen. Exit 0; 1 when the tempo/legs policy found no attempt that passes the checks
(the best attempt is still written); 2 for bad input.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from motion2robot.cli.numbers import FPS
from motion2robot.cli.read_options import add_read_options, read_args_kwargs
from motion2robot.cli.retarget_options import add_retarget_options, retarget_options_from, tempo_line
from motion2robot.errors import InputFileError, UserError
from motion2robot.util.output import output_path


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "retarget", help="retarget human motion onto a robot (casadi IK) and write the robot motion .npz",
        description="Retarget a human motion file onto a humanoid: scale from the clip's own bone "
                    "lengths, then solve every frame's IK (keypoints, limb directions, headings, "
                    "posture, smoothness) with joint and velocity limits, pinned soles in contact, "
                    "no sole below the floor, self-collision clearance and (by default) the CoM over "
                    "the support polygon. Writes an .npz with qpos, fps, joint_names, robot, meta.")
    p.add_argument("input", help="human motion file (HumanML3D joints/vecs, MDM results, BVH, npz, ...)")
    p.add_argument("--robot", default="op3", help="op3 (default), menagerie:NAME, or a robot MJCF/TOML path")
    p.add_argument("--clip", default=None, help="clip index of a multi-clip file, or 'all' (one output per clip)")
    p.add_argument("-o", "--output", help="output .npz (default: INPUT stem + '_<robot>.npz' beside the input)")
    p.add_argument("--fps", dest="out_fps", type=FPS, metavar="F",
                   help="frame rate of the robot motion (the human motion is resampled to it first; default: the file's)")
    p.add_argument("--iterations", type=_iterations, metavar="N[,M]", default=None,
                   help="Levenberg-Marquardt iterations of the free-feet and pinned stages (default 3,3: "
                        "the speed setting; 6,6 gives the per-frame IPOPT baseline's answer at about 80 %% of the speed)")
    add_retarget_options(p)
    add_read_options(p)
    p.set_defaults(func=run)


def _iterations(value: str) -> tuple[int, int]:
    try:
        parts = [int(x) for x in value.split(",")]
    except ValueError:
        parts = []
    if len(parts) not in (1, 2) or min(parts) < 1:
        raise argparse.ArgumentTypeError(f"{value!r}: give one or two positive whole numbers, e.g. 6 or 4,6")
    return (parts[0], parts[-1])


def _clip_arg(value: str | None) -> int | None | str:
    if value is None or value == "all":
        return value
    try:
        return int(value)
    except ValueError:
        raise UserError(f"--clip {value!r}: give a clip index (0, 1, ...) or 'all'") from None


def _output(args: argparse.Namespace, robot_name: str) -> Path:
    if args.output:
        return Path(args.output)
    safe = robot_name.replace("menagerie:", "").replace("/", "_").replace("\\", "_")
    return Path(args.input).with_name(f"{Path(args.input).stem}_{Path(safe).stem}.npz")


def summary(motion, clip_label: str, path: Path) -> str:
    """One line: frames, speed, worst constraint residual, mean keypoint error."""
    s = motion.meta["solver"]
    return (f"{clip_label}: {motion.num_frames} frames at {motion.fps:g} fps -> {path}  "
            f"({s['frames_per_s']:.0f} frames/s, keypoint error {1000 * sum(s['residual_per_frame']) / len(s['residual_per_frame']):.1f} mm, "
            f"worst constraint residual {1000 * s['max_constraint_residual']:.2f} mm)")


def run(args: argparse.Namespace) -> int:
    from motion2robot.motion import read_motion
    from motion2robot.retarget import RetargetOptions, retarget
    from motion2robot.robot import load_robot

    clip = _clip_arg(args.clip)
    robot = load_robot(args.robot)
    out = _output(args, robot.name)
    if args.output:  # a directory or a folder that cannot be made: said before the work, not after it
        output_path(out, "robot motion", ".npz")
    clips = read_motion(args.input, clip=None if clip in (None, "all") else clip, **read_args_kwargs(args))
    if not clips:
        raise InputFileError(f"{args.input}: no motion clip found; check the file")
    if len(clips) > 1 and clip is None:
        raise UserError(f"{args.input}: holds {len(clips)} clips; choose one with --clip 0..{len(clips) - 1} or --clip all")
    options = retarget_options_from(args, RetargetOptions(fps=args.out_fps))
    if args.iterations:
        options = replace(options, iterations=args.iterations)
    items = list(enumerate(clips))
    say = print
    if len(items) > 1:
        from tqdm import tqdm
        items, say = tqdm(items, desc="retarget", unit="clip"), tqdm.write  # lines above the bar
    from motion2robot.retarget.control_path import with_control_path

    status = 0
    for i, human in items:
        motion = with_control_path(retarget(human, robot, options), human)
        label = str(human.meta.get("clip", i))
        path = out if len(clips) == 1 else out.with_name(f"{out.stem}_clip{label}{out.suffix or '.npz'}")
        motion.save(path)
        say(summary(motion, f"clip {label}", path))
        if tempo_line(motion):
            say(f"  {tempo_line(motion)}")
        if motion.meta.get("executable") is False:  # judged, and no tempo/legs within the cap passes
            say(f"  not executable: written for inspection; `motion2robot check {path}` lists why")
            status = 1
    return status

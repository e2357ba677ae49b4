"""``motion2robot sim``: play a robot motion in the MuJoCo viewer, or render it to a video.

The input is a robot motion ``.npz`` (from ``motion2robot retarget``) or a human motion file,
which is retargeted on the fly. The scaled human skeleton is drawn beside the robot and the frames
that fail the feasibility checks are marked in red; ``--projected`` adds the robot's version in
the human's space over the human skeleton (:mod:`motion2robot.projection`).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from motion2robot.cli.motion_input import load_motion_input
from motion2robot.cli.numbers import number
from motion2robot.cli.read_options import add_read_options
from motion2robot.cli.retarget_options import add_retarget_options
from motion2robot.errors import UserError
from motion2robot.viz.camera import MODES
from motion2robot.viz.gl import prefer_headless
from motion2robot.viz.scene import PLACEMENTS, SceneOptions


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "sim", help="play a motion in the MuJoCo viewer or render it to a video",
        description="Play a robot motion (or a human motion, retargeted on the fly) in the MuJoCo viewer "
                    "with the scaled human skeleton beside the robot and failing frames in red; "
                    "keys: space pause, left/right step, up/down speed, F next failing frame, L loop. "
                    "With --render, write an MP4/GIF offscreen instead (no display needed).")
    p.add_argument("input", metavar="MOTION", help="robot motion .npz, or a human motion file (BVH, HumanML3D, ...)")
    p.add_argument("--robot", help="robot (op3, menagerie:unitree_g1, a config path); default: the motion's robot, else op3")
    p.add_argument("--clip", type=int, help="clip index of a multi-clip human motion file")
    p.add_argument("--physics", action="store_true", help="play the physics rollout instead of the kinematic replay")
    p.add_argument("--render", metavar="OUT", help="render offscreen to OUT (.mp4 or .gif) instead of opening the viewer")
    p.add_argument("--size", default="640x480", help="video size WIDTHxHEIGHT in pixels (default 640x480)")
    p.add_argument("--camera", choices=MODES, default="follow", help="follow the subjects or frame the whole path (default follow)")
    p.add_argument("--video-fps", type=number("frames per second", 1.0, 1000.0), help="video frame rate (default: the motion's, at most 30)")
    p.add_argument("--human", choices=PLACEMENTS, default="beside", help="draw the human skeleton beside the robot, over it, or not")
    p.add_argument("--projected", action="store_true",
                   help="also draw the robot's version in the human's space (blue, over the human skeleton): "
                        "the robot's keypoints mapped back to the human's scale and tempo")
    p.add_argument("--no-check", action="store_true", help="skip the feasibility checks (no failing frames marked)")
    p.add_argument("--once", action="store_true", help="viewer: stop at the last frame instead of looping")
    p.add_argument("--speed", type=number("x (1 = real time)", 0.0, 100.0, low_open=True), default=1.0, help="viewer playback speed (default 1)")
    p.add_argument("--pretty", action="store_true", help="video: shadows and reflections (slower)")
    add_retarget_options(p)
    add_read_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    prefer_headless()  # no display and no MUJOCO_GL: EGL
    from motion2robot.robot.world import make_world
    from motion2robot.viz.physics import rollout_qpos
    from motion2robot.viz.render import output_frames, parse_size, render_frames, write_video
    from motion2robot.viz.scene import make_playable

    size = parse_size(args.size)
    if args.render and Path(args.render).suffix.lower() not in (".mp4", ".gif"):
        raise UserError(f"--render {args.render}: unknown video type; use a name ending in .mp4 or .gif")
    motion, robot, human = load_motion_input(args.input, args)
    report = None
    if not args.no_check:
        from motion2robot.validate import CheckOptions, check

        report = check(motion, robot, CheckOptions(physics=args.physics))
    qpos = rollout_qpos(motion, robot, report) if args.physics else None
    play = make_playable(motion, robot, human=human, report=report, options=SceneOptions(human=args.human, projected=args.projected), qpos=qpos)
    world = make_world(robot)
    if not args.render:
        from motion2robot.viz.viewer import play_in_viewer

        play_in_viewer(world, play, loop=not args.once, speed=args.speed, camera=args.camera)
        return 0
    out_fps = args.video_fps or min(play.fps, 30.0)
    frames = output_frames(play.num_frames, play.fps, out_fps)
    t0 = time.perf_counter()
    images = render_frames(world, play, frames, size=size, camera=args.camera, pretty=args.pretty)
    path = write_video(_progress(images, len(frames)), args.render, out_fps)
    dt = time.perf_counter() - t0
    failing = len(play.failing)
    print(f"wrote {path} ({len(frames)} frames, {size[0]}x{size[1]}, {out_fps:g} fps; rendered in {dt:.1f} s"
          f"{f'; {failing} failing frames marked' if failing else ''})")
    return 0


def _progress(images, total: int):
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover
        return images
    return tqdm(images, total=total, desc="rendering", unit="frame", disable=not sys.stderr.isatty(), leave=False)


"""``motion2robot inspect FILE``: what a motion file holds, as the pipeline will read it."""

from __future__ import annotations

import argparse
from pathlib import Path

from motion2robot.cli.read_options import add_read_options, read_args_kwargs
from motion2robot.errors import InputFileError


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "inspect", help="show what a motion file holds (format, clips, frames, fps, height, contacts)",
        description="Read a motion file (or folder) as the pipeline does and describe each clip: "
                    "detected format, frames, fps, duration, subject height, up-axis decision, "
                    "foot contacts and text prompt.")
    from motion2robot.motion.formats import SCAN_SUFFIXES

    p.add_argument("file", help=f"motion file or folder ({' '.join(SCAN_SUFFIXES)}; see --format)")
    p.add_argument("--clip", type=int, help="only this clip index")
    p.add_argument("--plot", metavar="OUT.png", help="draw the skeleton at a few frames and the root path")
    add_read_options(p)
    p.set_defaults(func=run)


def describe(m, index: int, total: int) -> str:
    """A readable block of lines about one clip."""
    from motion2robot.motion.contacts import with_contacts
    from motion2robot.motion.height import subject_height

    meta = m.meta
    mc = with_contacts(m)
    left, right = mc.contacts.mean(axis=0) * 100
    lines = [
        f"clip {meta.get('clip', index)} ({index + 1} of {total})",
        f"  frames      {m.num_frames} at {m.fps:g} fps = {m.duration:.2f} s"
        + (f" (file says {meta['source_fps']:g} fps)" if abs(meta.get('source_fps', m.fps) - m.fps) > 1e-6 else ""),
        f"  height      {subject_height(m):.2f} m",
        f"  up axis     {meta.get('up_axis')} ({meta.get('up_axis_source')})",
        f"  units       {meta.get('units')} ({meta.get('units_source')})",
        f"  contacts    left {left:.0f} %, right {right:.0f} % of frames ({mc.meta['contacts_source']})",
    ]
    for key, label in (("skeleton", "skeleton"), ("joint_map", "mapping"), ("features", "features"),
                       ("dropped", "dropped"), ("note", "note")):
        if meta.get(key) is not None:
            lines.append(f"  {label:<11} {meta[key]}")
    if meta.get("control_path"):
        n = sum(p is not None for p in meta["control_path"])
        lines.append(f"  control     requested root path in {n} of {m.num_frames} frames ({meta.get('control_source')})")
    elif meta.get("control_note"):
        lines.append(f"  control     {meta['control_note']}")
    if meta.get("prompt"):
        lines.append(f"  prompt      \"{meta['prompt']}\"")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from motion2robot.motion.read import detect_format, read_motion

    fmt = args.format or detect_format(args.file)
    clips = read_motion(args.file, clip=args.clip, **{**read_args_kwargs(args), "format": fmt})
    how = "given" if args.format else "detected"
    print(f"{args.file}: format {fmt} ({how}), {len(clips)} clip{'s' if len(clips) != 1 else ''}")
    for i, m in enumerate(clips):
        print(describe(m, i, len(clips)))
    if args.plot:
        from motion2robot.motion.plot import plot_motion

        from motion2robot.util.output import output_path

        out = output_path(args.plot, "plot", ".png")
        m = clips[0]
        prompt = m.meta.get("prompt")
        title = f"{Path(args.file).name} clip {m.meta.get('clip', 0)}" + (f": {prompt}" if prompt else "")
        plot_motion(m, out, title=title)
        print(f"plot written to {out} (clip {m.meta.get('clip', 0)})")
    return 0

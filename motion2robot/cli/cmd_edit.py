"""``motion2robot edit SOURCE [EDITED]``: an edit pair on the robot, keeping what the edit did not change.

Writes both robot motions (``<stem>_source_<robot>.npz``, ``<stem>_edited_<robot>.npz``), prints the
diff (human parts changed, robot hinges changed, where balance overrode the kept joints and why,
feasibility of both, what the edit broke or fixed)
and with ``--json`` writes it as JSON. Exit code 0 when the edited motion is feasible, 1 when not.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from motion2robot.cli.numbers import number
from motion2robot.cli.read_options import add_read_options, read_args_kwargs
from motion2robot.cli.retarget_options import add_retarget_options, retarget_options_from
from motion2robot.errors import InputFileError, UserError


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "edit", help="retarget an edit pair: the edit keeps the source's robot motion wherever it did not change",
        description="Read a source motion and its edit (two files of any readable format, or one editor result "
                    "file holding both), compare them per body part and frame on the frames both have (the edit "
                    "resampled to the source's rate), retarget the source, and retarget the edit so that every "
                    "robot joint driven by an unedited part keeps exactly the source's trajectory, with a smooth "
                    "blend of bounded length where the edit starts and ends. Where keeping those joints exactly "
                    "makes the edit lose its balance or overload a joint (and the edit's own solution does not), "
                    "balance overrides them in those frames only, and says where and why. Prints which parts "
                    "and joints changed and the feasibility of both. Exit 0 if the edit is feasible, 1 if not, "
                    "2 on error.")
    p.add_argument("source", help="source motion file, or an editor result file holding source and edit")
    p.add_argument("edited", nargs="?", help="edited motion file (omit for an editor result file)")
    p.add_argument("--robot", default="op3", help="robot name or config path (default: op3)")
    p.add_argument("--source-clip", type=int, help="clip of a multi-clip source file")
    p.add_argument("--edit-clip", type=int, help="clip of a multi-clip edited file")
    p.add_argument("--tolerance", type=number("m", 0.0, 10.0), default=None, metavar="M",
                   help="a body part is unedited in a frame where its joints (relative to the pelvis) move less "
                        "than this between source and edit (metres; default 0.02)")
    p.add_argument("--blend", type=number("s", 0.0, 60.0), default=None, metavar="S", help="blend length in seconds (default 0.25)")
    p.add_argument("-o", "--out-dir", help="folder for the two robot motions (default: beside the edited file)")
    p.add_argument("--json", metavar="DIFF.json", help="write the diff and both feasibility reports as JSON")
    p.add_argument("--html", metavar="REPORT.html",
                   help="write the edited motion's HTML report with the diff against the source")
    p.add_argument("--no-physics", dest="physics", action="store_false", help="skip the physics playback")
    p.add_argument("--no-balance-override", dest="balance_override", action="store_false",
                   help="keep the unchanged joints exactly the source's even where the composed edit then loses its "
                        "balance or overloads a joint (the edit is then reported infeasible there, with the reason); "
                        "by default balance overrides them in those frames only, and says so")
    add_retarget_options(p)
    add_read_options(p)
    p.set_defaults(func=run)


def _one(path: str, clip: int | None, args: argparse.Namespace):
    from motion2robot.motion import read_motion

    clips = read_motion(path, clip=clip, **read_args_kwargs(args))
    if len(clips) != 1:
        raise UserError(f"{path}: holds {len(clips)} clips; choose one with --source-clip/--edit-clip")
    return clips[0]


def _pair(args: argparse.Namespace):
    from motion2robot.motion import read_motion

    if args.edited:
        return _one(args.source, args.source_clip, args), _one(args.edited, args.edit_clip, args), Path(args.edited)
    clips = read_motion(args.source, **read_args_kwargs(args))
    roles = {c.meta.get("role"): c for c in clips}
    if "source" not in roles or "edited" not in roles:
        raise InputFileError(f"{args.source}: holds no (source, edited) pair; give SOURCE and EDITED files, "
                             "or an editor result file with pose and pose_source")
    return roles["source"], roles["edited"], Path(args.source)


def override_lines(o: dict | None) -> list[str]:
    """What the balance override did (or, forbidden, would have had to do), and why."""
    if not o:
        return []
    out = []
    if o["frames"]:
        why = "; ".join(o["why"])
        if o["applied"]:
            joints = ", ".join(f"{j} ({f})" for j, f in o["joints"].items()) or "none"
            out.append(f"balance overrode the unchanged joints in frames {o['frames']}: keeping them exactly the "
                       f"source's fails there ({why}); the edit's own solution is used there, blended. "
                       f"Joints moved off the source's: {joints}")
        else:
            out.append(f"the edit is infeasible in frames {o['frames']} with the unchanged joints kept exactly the "
                       f"source's ({why}); --no-balance-override forbids the override that would fix it")
    if o.get("unresolved_frames"):
        out.append(f"the edit fails balance or torque in frames {o['unresolved_frames']} whatever the unchanged "
                   "joints do (its own solution fails there too)")
    return out


def diff_text(result, rep_src, rep_edit) -> str:
    lines = []
    if not result.human:
        lines.append("human edit: changes nothing (every part within the tolerance in every frame)")
    for part, d in result.human.items():
        lines.append(f"human edit: {part} changed in frames {d['frames']} (up to {d['max_m'] * 100:.1f} cm)")
    for joint, d in result.robot.items():
        unit = f"{math.degrees(d['max_rad']):.1f} deg" if joint != "root" else f"{d['max_rad']:.3f} (m / quaternion)"
        lines.append(f"robot: {joint} differs from the source's in frames {d['frames']} (up to {unit})")
    same = [j for j in result.source.joint_names if j not in result.robot]
    lines.append(f"robot: {len(same)} of {len(result.source.joint_names)} joints"
                 f"{'' if 'root' in result.robot else ' and the root'} equal the source's robot motion in every frame")
    lines += override_lines(result.info.get("balance_override"))
    lines.append(f"feasible: source {'yes' if rep_src.feasible else 'no'}, edit {'yes' if rep_edit.feasible else 'no'}")
    for r in rep_edit.reasons:
        if r not in rep_src.reasons:
            lines.append(f"the edit breaks: {r}")
    for r in rep_src.reasons:
        if r not in rep_edit.reasons:
            lines.append(f"the edit fixes: {r}")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from motion2robot.edit import retarget_edit
    from motion2robot.edit.pair import BLEND_SECONDS
    from motion2robot.edit.parts import TOLERANCE
    from motion2robot.robot import load_robot
    from motion2robot.validate import CheckOptions, check

    robot = load_robot(args.robot)
    source, edited, where = _pair(args)
    result = retarget_edit(source, edited, robot, retarget_options_from(args),
                           tolerance=TOLERANCE if args.tolerance is None else args.tolerance,
                           blend_seconds=BLEND_SECONDS if args.blend is None else args.blend,
                           balance_override=args.balance_override,
                           name=f"{args.source} + {args.edited or '(its edit)'}")
    out_dir = Path(args.out_dir) if args.out_dir else where.parent
    out_dir.mkdir(parents=True, exist_ok=True)
    tag = robot.name.replace("menagerie:", "").replace("/", "_")
    paths = [result.source.save(out_dir / f"{where.stem}_source_{tag}.npz"),
             result.edited.save(out_dir / f"{where.stem}_edited_{tag}.npz")]
    opts = CheckOptions(physics=args.physics)
    rep_src, rep_edit = check(result.source, robot, opts), check(result.edited, robot, opts)
    forbidden = bool((result.info.get("balance_override") or {}).get("frames")) and not args.balance_override
    print(diff_text(result, rep_src, rep_edit))
    print("robot motions written to " + ", ".join(str(p) for p in paths))
    if args.json:
        from motion2robot.util.jsonable import plain

        doc = {"human_parts_changed": result.human, "robot_joints_changed": result.robot, "info": result.info,
               "balance_override": result.info.get("balance_override"),
               "edit_executable": bool(rep_edit.feasible and not forbidden),
               "source_report": rep_src.to_dict(), "edit_report": rep_edit.to_dict(),
               "breaks": [r for r in rep_edit.reasons if r not in rep_src.reasons],
               "fixes": [r for r in rep_src.reasons if r not in rep_edit.reasons]}
        Path(args.json).write_text(json.dumps(plain(doc), indent=1))
        print(f"diff written to {args.json}")
    if args.html:
        import html

        from motion2robot.viz.html_report import write_html_report

        body = "<ul>" + "".join(f"<li>{html.escape(x)}</li>" for x in diff_text(result, rep_src, rep_edit).splitlines()) + "</ul>"
        path = write_html_report(rep_edit, result.edited, robot, args.html, human=edited,
                                 sections=[("Edit against the source", body)])
        print(f"HTML report written to {path}")
    return 0 if rep_edit.feasible and not forbidden else 1

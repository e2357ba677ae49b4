"""``motion2robot robots``: list the known robots, show one, or draft a config for a new humanoid.

    motion2robot robots                                  # list (name, origin, DOF, mass, height)
    motion2robot robots show NAME                        # joints, limits, servos, feet, keypoints
    motion2robot robots init MODEL.xml|menagerie:NAME -o NAME.toml [--force]
    motion2robot robots compare DRAFT.toml menagerie:NAME   # two configs of one model
"""

from __future__ import annotations

import argparse
from pathlib import Path

from motion2robot.errors import UserError
from motion2robot.robot.describe import compare_robots, joint_rows, keypoint_rows, known_robots, model_top
from motion2robot.robot.loader import load_robot
from motion2robot.robot.robot import Robot


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "robots", help="list known robots, show one, draft a config for a new humanoid, compare two configs",
        description="Without a subcommand: list the robots motion2robot knows and where each comes from.",
    )
    p.set_defaults(func=_list)
    sub = p.add_subparsers(dest="robots_command", metavar="{show,init,compare}")
    show = sub.add_parser("show", help="joints with limits, servo IDs, mass, height, feet and keypoint map",
                          description="Show a robot: op3 | menagerie:NAME | path to an MJCF (with .toml beside) or TOML.")
    show.add_argument("name", help="robot name: op3 | menagerie:NAME | path to MJCF/TOML")
    show.add_argument("--render", metavar="OUT.png",
                      help="also draw the robot at its nominal pose with its keypoints and soles marked (offscreen: "
                           "MUJOCO_GL=egl or osmesa)")
    show.set_defaults(func=_show)
    init = sub.add_parser(
        "init", help="draft a robot config (.toml) for a humanoid MJCF motion2robot has not seen",
        description="Guess pelvis, legs, arms, head, feet and limits from the kinematic tree and names, "
                    "write a TOML config, and list what needs a human look.")
    init.add_argument("model", help="MODEL.xml or menagerie:NAME")
    init.add_argument("-o", "--output", required=True, help="where to write the config, e.g. NAME.toml")
    init.add_argument("--name", help="robot name written into the config (default: from the output file name)")
    init.add_argument("--force", action="store_true", help="overwrite an existing output file")
    init.set_defaults(func=_init)
    cmp_ = sub.add_parser("compare", help="compare two configs of the same model (e.g. a draft with a shipped config)",
                          description="Keypoint bodies and distances at the second robot's nominal pose, sole "
                                      "rectangles, limits and gains of two configs of one MJCF.")
    cmp_.add_argument("a", help="robot name or config path (e.g. the draft)")
    cmp_.add_argument("b", help="robot name or config path (the reference; its nominal pose is used)")
    cmp_.set_defaults(func=_compare)


def _fmt(v: float | None, spec: str, unit: str = "") -> str:
    return "-" if v is None else f"{v:{spec}}{unit}"


def _list(args: argparse.Namespace) -> int:
    entries = known_robots()
    rows = [("NAME", "ORIGIN", "AVAILABLE", "DOF", "MASS", "HEIGHT", "WHERE")]
    for e in entries:
        rows.append((e.name, e.origin, "yes" if e.available else "no", _fmt(e.dof, "d"),
                     _fmt(e.mass, ".2f", " kg"), _fmt(e.height, ".3f", " m"), e.error or e.where))
    _table(rows)
    print("\nAlso: any MJCF path with a .toml beside it (draft one with 'motion2robot robots init MODEL.xml -o NAME.toml').")
    return 0


def _show(args: argparse.Namespace) -> int:
    robot = load_robot(args.name)
    print(describe_robot(robot))
    if args.render:
        from motion2robot.viz.keypoint_image import write_keypoint_image

        print(f"\nwrote {write_keypoint_image(robot, args.render)} (keypoints: left blue, right red, trunk yellow; soles green)")
    return 0


def describe_robot(robot: Robot) -> str:
    """A readable multi-line description of ``robot`` (what ``robots show`` prints)."""
    cfg = robot.config
    lines = [f"{robot.name}: {cfg.description or cfg.name}",
             f"  source     {robot.source}",
             f"  mjcf       {robot.mjcf_path}",
             f"  config     {cfg.path}",
             f"  model hash {robot.model_hash}",
             f"  joints     {robot.n_joints} hinges + free root ({cfg.root_body}); torso body {cfg.torso_body}",
             f"  mass       {robot.mass:.3f} kg",
             f"  height     {robot.height:.3f} m (highest keypoint at the nominal pose); "
             f"top of the model {model_top(robot):.3f} m",
             ""]
    servos = cfg.servos is not None
    head = ["JOINT", "LOWER rad", "UPPER rad", "LOWER deg", "UPPER deg", "VEL rad/s", "TORQUE N*m", "KP", "NOMINAL rad"]
    head += ["SERVO ID"] if servos else []
    rows = [tuple(head)]
    for j in joint_rows(robot):
        row = [j.name, f"{j.lower:+.3f}", f"{j.upper:+.3f}", f"{j.lower_deg:+.1f}", f"{j.upper_deg:+.1f}",
               f"{j.velocity:.2f}", f"{j.torque:.2f}", f"{j.kp:g}", f"{j.nominal:+.3f}"]
        rows.append(tuple(row + ([str(j.servo_id) if j.servo_id is not None else "-"] if servos else [])))
    lines += _table(rows, emit=False)
    if servos:
        s = cfg.servos
        lines += ["", f"servos: {s.model}, {s.baud} baud, {s.ticks_per_rev} ticks/rev, centre {s.center}"]
    lines += ["", "feet (sole rectangle in the foot body's frame, m):"]
    for f in cfg.feet:
        c, h = f.sole_center, f.sole_half
        lines.append(f"  {f.side:5s} {f.body}: centre ({c[0]:+.4f}, {c[1]:+.4f}, {c[2]:+.4f}), "
                     f"size {2 * h[0]:.3f} x {2 * h[1]:.3f}")
    lines += ["", "keypoints (SMPL -> robot):"]
    kp_rows = [("HUMAN", "ROBOT", "OFFSET m", "WEIGHT")]
    for k, (_, body, pos, w) in zip(cfg.keypoints, keypoint_rows(robot)):
        target = f"site {k.site} on {body}" if k.site else f"body {body}"
        kp_rows.append((k.human, target, "(" + ", ".join(f"{v:+.3f}" for v in pos) + ")", f"{w:g}"))
    lines += ["  " + ln for ln in _table(kp_rows, emit=False)]
    scale = ", ".join(f"{k} = {v:g}" for k, v in cfg.scale.items()) or "none (automatic)"
    lines += ["", f"scale overrides: {scale}"]
    reasons = [(j.name, j.reason) for j in joint_rows(robot) if j.reason]
    if reasons:
        lines += ["", "range notes:"] + [f"  {n}: {r}" for n, r in reasons]
    return "\n".join(lines)


def _table(rows: list[tuple[str, ...]], emit: bool = True) -> list[str]:
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    out = ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
    if emit:
        print("\n".join(out))
    return out


def _init(args: argparse.Namespace) -> int:
    from motion2robot.robot.draft import draft_config, write_draft

    out = Path(args.output)
    if out.exists() and not args.force:
        raise UserError(f"{out}: already exists; pass --force to overwrite it or choose another -o path")
    name = args.name or out.stem
    draft = draft_config(args.model, name=name)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise UserError(f"{out.parent}: cannot create the output folder ({err.strerror}); choose another -o path") from err
    write_draft(draft, out)
    print(f"wrote {out} (draft config for {args.model}: {draft.n_joints} hinges)")
    print("\nkeypoints:")
    rows = [("HUMAN", "ROBOT BODY", "OFFSET m", "WHY")]
    for k in draft.keypoints:
        rows.append((k.human, k.body, "(" + ", ".join(f"{v:+.3f}" for v in k.offset) + ")", k.note or "-"))
    print("\n".join("  " + ln for ln in _table(rows, emit=False)))
    print("\nguessed:")
    for g in draft.guesses:
        print(f"  - {g}")
    if draft.checks:
        print("\nneeds a human look (marked CHECK in the file):")
        for c in draft.checks:
            print(f"  - {c}")
    print(f"\nnominal height (highest keypoint): {draft.height:.3f} m")
    print(f"next: edit the CHECK lines, then 'motion2robot robots show {out}'")
    return 0


def _compare(args: argparse.Namespace) -> int:
    a, b = load_robot(args.a), load_robot(args.b)
    gaps, soles = compare_robots(a, b)
    print(f"A = {a.name}\nB = {b.name} (keypoints compared at B's nominal pose)\n")
    rows = [("KEYPOINT", "A BODY", "B BODY", "SAME", "GAP mm")]
    for g in gaps:
        rows.append((g.human, g.body_a or "-", g.body_b or "-", "yes" if g.body_a == g.body_b else "NO",
                     "-" if g.gap is None else f"{1000 * g.gap:.1f}"))
    _table(rows)
    print()
    for f, d in zip(("left", "right"), soles):
        print(f"{f} sole: " + ("different foot bodies" if d != d else f"corners differ by at most {1000 * d:.1f} mm"))
    rows = [("JOINT", "RANGE A", "RANGE B", "VEL A", "VEL B", "TORQUE A", "TORQUE B", "KP A", "KP B", "NOMINAL A", "NOMINAL B")]
    for ja, jb in zip(joint_rows(a), joint_rows(b)):
        rows.append((ja.name, f"[{ja.lower:+.2f}, {ja.upper:+.2f}]", f"[{jb.lower:+.2f}, {jb.upper:+.2f}]",
                     f"{ja.velocity:g}", f"{jb.velocity:g}", f"{ja.torque:g}", f"{jb.torque:g}",
                     f"{ja.kp:g}", f"{jb.kp:g}", f"{ja.nominal:+.3f}", f"{jb.nominal:+.3f}"))
    print()
    _table(rows)
    print(f"\nheight A {a.height:.3f} m, B {b.height:.3f} m")
    return 0

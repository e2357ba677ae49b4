"""One self-contained HTML page for a feasibility report: verdict table, reasons, plots and a strip
of rendered key frames (first, worst, last). Inline CSS; images are base64 PNG data URIs, so the
file can be mailed or archived alone.
"""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from motion2robot.errors import UserError
from motion2robot.motion.human import HumanMotion
from motion2robot.robot.poses import frame_poses
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.util.ranges import frame_ranges
from motion2robot.viz import plots
from motion2robot.viz.scene import failing_frames

if TYPE_CHECKING:
    from motion2robot.validate import FeasibilityReport


CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:2em auto;max-width:1000px;color:#222;padding:0 1em}
h1{font-size:1.5em;margin-bottom:.2em}h2{font-size:1.15em;margin-top:1.8em;border-bottom:1px solid #ddd;padding-bottom:.2em}
.meta{color:#555;font-size:.9em}.verdict{display:inline-block;padding:.3em .8em;border-radius:4px;font-weight:bold;color:#fff}
.ok{background:#27ae60}.fail{background:#c0392b}table{border-collapse:collapse;width:100%;font-size:.9em}
td,th{border:1px solid #ddd;padding:.35em .6em;text-align:left;vertical-align:top}th{background:#f4f4f4}
td.pass{color:#27ae60;font-weight:bold}td.failc{color:#c0392b;font-weight:bold}
figure{margin:1em 0}figure img{max-width:100%;border:1px solid #eee}figcaption{font-size:.85em;color:#555}
.strip{display:flex;gap:8px;flex-wrap:wrap}.strip figure{margin:0;flex:1;min-width:200px}
""".strip()


def _img(png: bytes, alt: str) -> str:
    data = base64.b64encode(png).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" alt="{html.escape(alt)}">'


def _fmt(v: Any) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (float, np.floating)):
        return f"{float(v):.4g}"
    if isinstance(v, (list, tuple)) and v and all(isinstance(x, dict) for x in v):
        joints = [str(x["joint"]) for x in v if "joint" in x]
        return f"{len(v)} entries" + (f" ({', '.join(joints[:6])}{', ...' if len(joints) > 6 else ''})" if joints else "")
    if isinstance(v, (list, tuple, dict)) and len(v) > 6:
        return f"[{len(v)} values]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k}: {_fmt(x)}" for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return str(v)


def sole_corners_xy(motion: RobotMotion, robot: Robot) -> np.ndarray:
    """(T, 2, 4, 2) ground projection (m) of the sole corners [left, right] per frame."""
    sites = frame_poses(robot.model, motion.qpos, np.asarray(robot.sole_sites).ravel()).sites
    return sites.reshape(motion.num_frames, 2, 4, 3)[..., :2].copy()


def report_plots(report: Any, motion: RobotMotion, robot: Robot) -> list[tuple[str, bytes]]:
    """[(alt text, PNG)] for the evidence present in ``report.series``."""
    s = report.series
    fps, names = motion.fps, robot.joint_names
    fail = failing_frames(report)
    out: list[tuple[str, bytes]] = []

    def add(alt: str, fig: Any) -> None:
        out.append((alt, plots.figure_png(fig)))

    def frames_of(check: str) -> list[int]:
        res = report.checks.get(check, {})
        return [] if res.get("ok", True) else list(res.get("frames") or [])

    if "q" in s:
        add("joint angles against limits", plots.plot_joint_angles(
            np.asarray(s["q"]), robot.lower, robot.upper, names, fps, frames_of("joint_limits")))
    if "qvel" in s:
        ratio = np.abs(np.asarray(s["qvel"])) / np.maximum(robot.velocity_limit, 1e-9)
        add("joint speeds", plots.plot_ratio(ratio, names, fps, "Joint speeds against velocity limits",
                                             "|speed| / limit", frames_of("velocity_limits")))
    if "torque_ratio" in s:
        add("torque ratios", plots.plot_ratio(np.asarray(s["torque_ratio"]), names, fps,
                                              "Joint torques against torque limits", "|torque| / limit",
                                              frames_of("torque_limits")))
    if "com_xy" in s:
        balance_bad = sorted(f for f, names_ in fail.items() if "balance" in names_)
        add("CoM and ZMP against the support polygon", plots.plot_balance(
            np.asarray(s["com_xy"]), _opt(s, "zmp_xy"), sole_corners_xy(motion, robot),
            _opt(s, "contacts"), _opt(s, "support_margin"), fps, balance_bad, _opt(s, "zmp_margin")))
    if "foot_height" in s:
        add("foot heights and contact phases", plots.plot_feet(np.asarray(s["foot_height"]), _opt(s, "contacts"), fps))
    return out


def _opt(series: Any, key: str) -> np.ndarray | None:
    return np.asarray(series[key]) if key in series and series[key] is not None else None


def worst_frame(report: Any, n_frames: int) -> int:
    """The frame where most checks fail (ties: smallest support margin); without failures the
    frame of the smallest support margin, else the middle frame."""
    counts = np.zeros(n_frames)
    for f, names in failing_frames(report).items():
        if 0 <= f < n_frames:
            counts[f] = len(names)
    margin = report.series.get("support_margin") if hasattr(report, "series") else None
    m = np.asarray(margin, dtype=float) if margin is not None and len(margin) == n_frames else np.zeros(n_frames)
    if counts.any():
        return int(np.lexsort((m, -counts))[0])
    return int(np.argmin(m)) if margin is not None and len(margin) == n_frames else n_frames // 2


def key_frames(report: Any, n_frames: int) -> list[tuple[str, int]]:
    """[(caption, frame)] for first, worst and last."""
    return [("first", 0), ("worst", worst_frame(report, n_frames)), ("last", n_frames - 1)]


def render_key_frames(report: Any, motion: RobotMotion, robot: Robot, human: HumanMotion | None,
                      size: tuple[int, int] = (320, 240)) -> list[tuple[str, int, bytes]]:
    """[(caption, frame, PNG)] rendered offscreen (raises UserError when OpenGL is unavailable)."""
    from PIL import Image

    from motion2robot.robot.world import make_world
    from motion2robot.viz.render import render_frames
    from motion2robot.viz.scene import make_playable

    from motion2robot.viz.scene import SceneOptions

    keys = key_frames(report, motion.num_frames)
    play = make_playable(motion, robot, human=human, report=report, options=SceneOptions(projected=True))
    images = render_frames(make_world(robot), play, [f for _, f in keys], size=size, camera="follow")
    out = []
    for (cap, f), img in zip(keys, images):
        buf = io.BytesIO()
        Image.fromarray(img).save(buf, format="PNG")
        out.append((cap, f, buf.getvalue()))
    return out


def _checks_table(report: Any) -> str:
    rows = ["<tr><th>check</th><th>result</th><th>frames</th><th>figures</th></tr>"]
    for name, res in report.checks.items():
        ok = bool(res.get("ok", True))
        frames = res.get("frames") or []
        figs = ", ".join(f"{html.escape(str(k))}={html.escape(_fmt(v))}" for k, v in res.items()
                         if k not in ("ok", "frames", "skipped"))
        if res.get("skipped"):
            cls, word, figs = "", "skipped", html.escape(str(res["skipped"]))
        else:
            cls, word = ("pass", "PASS") if ok else ("failc", "FAIL")
        rows.append(f"<tr><td>{html.escape(name)}</td><td class=\"{cls}\">{word}</td>"
                    f"<td>{html.escape(frame_ranges(frames)) or '&ndash;'}</td><td>{figs}</td></tr>")
    return '<table class="verdict-table">' + "".join(rows) + "</table>"


def projection_section(motion: RobotMotion, robot: Robot, human: HumanMotion | None) -> tuple[str, str] | None:
    """("The robot's version in the human's space", HTML) : the per-joint distance (cm, mean and
    largest over frames) between the human and the robot's keypoints mapped back onto the human
    skeleton (:func:`motion2robot.projection.project_motion`); None when the human or the
    retargeter's meta is unknown."""
    from motion2robot.projection import joint_distance, project_motion
    from motion2robot.viz.scene import load_source_human

    human = human if human is not None else load_source_human(motion.meta)
    if human is None:
        return None
    try:
        d = joint_distance(human.positions, project_motion(motion, robot, human).positions)
    except UserError:
        return None
    from motion2robot.motion.human import SMPL22

    order = np.argsort(-d.mean(axis=0))
    rows = "".join(f"<tr><td>{SMPL22[j]}</td><td>{100 * d[:, j].mean():.1f}</td><td>{100 * d[:, j].max():.1f}</td></tr>"
                   for j in order)
    body = (f"<p>The robot's keypoints mapped back onto the human skeleton at the human's scale and tempo "
            f"(blue skeleton in the key frames, over the human's): {100 * d.mean():.1f} cm from the human on "
            f"average. Distance per joint, cm:</p><table><tr><th>joint</th><th>mean</th><th>largest</th></tr>"
            f"{rows}</table>")
    return "The robot's version in the human's space", body


def _list(items: Sequence[str]) -> str:
    return "<ul>" + "".join(f"<li>{html.escape(str(i))}</li>" for i in items) + "</ul>"


def render_html(report: Any, motion: RobotMotion, robot: Robot, *, human: HumanMotion | None = None,
                keyframes: bool = True, sections: Sequence[tuple[str, str]] = ()) -> str:
    """The report page as a string (see :func:`write_html_report`); ``sections``: extra (title,
    HTML body) pairs shown after the reasons (e.g. an edit's diff)."""
    meta = motion.meta
    title = f"motion2robot feasibility: {Path(str(meta.get('source', 'motion'))).name} on {robot.name}"
    ok = bool(report.feasible)
    parts = [f"<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{html.escape(title)}</title>"
             f"<style>{CSS}</style></head><body><h1>{html.escape(title)}</h1>",
             f"<p><span class=\"verdict {'ok' if ok else 'fail'}\">{'FEASIBLE' if ok else 'NOT FEASIBLE'}</span></p>"]
    facts = {"robot": robot.name, "source": meta.get("source"), "clip": meta.get("clip"), "prompt": meta.get("prompt"),
             "frames": motion.num_frames, "fps": f"{motion.fps:g}", "duration": f"{motion.duration:.2f} s"}
    parts.append('<p class="meta">' + " &middot; ".join(f"{k}: {html.escape(str(v))}" for k, v in facts.items()
                                                          if v not in (None, "")) + "</p>")
    if meta.get("tempo") is not None:
        tempo = f"Tempo x{float(meta['tempo']):.2f}: {meta.get('tempo_reason', '')}"
        fb = meta.get("fallback")
        legs = (f"Legs: {fb['mode']}, because {fb['why']}; {fb.get('what', '')}" if fb else "Legs: whole body, as generated.")
        parts.append(f"<h2>Tempo and legs</h2>{_list([tempo, legs])}")
    parts.append("<h2>Reasons</h2>" + (_list(report.reasons) if report.reasons else "<p>None: every check passed.</p>"))
    projected = projection_section(motion, robot, human)
    parts += [f"<h2>{html.escape(t)}</h2>{body}" for t, body in (*sections, *([projected] if projected else []))]
    parts.append("<h2>Checks</h2>" + _checks_table(report))
    if getattr(report, "figures", None):
        parts.append("<h2>Figures</h2><table>" + "".join(
            f"<tr><th>{html.escape(str(k))}</th><td>{html.escape(_fmt(v))}</td></tr>" for k, v in report.figures.items()
            if not isinstance(v, dict)) + "</table>")
    parts.append('<h2>Plots</h2><div class="plots">')
    for alt, png in report_plots(report, motion, robot):
        parts.append(f"<figure>{_img(png, alt)}<figcaption>{html.escape(alt)}</figcaption></figure>")
    parts.append("</div>")
    if keyframes:
        parts.append('<h2>Key frames</h2>')
        try:
            shots = render_key_frames(report, motion, robot, human)
        except UserError as err:
            parts.append(f"<p>Key frames not rendered: {html.escape(str(err))}</p>")
        else:
            parts.append('<div class="strip">' + "".join(
                f"<figure>{_img(png, f'key frame {cap} (frame {f})')}<figcaption>{cap}: frame {f} "
                f"(t = {f / motion.fps:.2f} s)</figcaption></figure>" for cap, f, png in shots) + "</div>")
    parts.append("</body></html>")
    return "\n".join(parts)


def write_html_report(report: "FeasibilityReport", motion: RobotMotion, robot: Robot, path: str | Path, *,
                      human: HumanMotion | None = None, keyframes: bool = True,
                      sections: Sequence[tuple[str, str]] = ()) -> Path:
    """Write the self-contained HTML page for ``report`` (a FeasibilityReport of ``motion`` on
    ``robot``) to ``path``; ``human`` (optional) is drawn beside the robot in the key frames.
    Returns the path."""
    path = Path(path)
    text = render_html(report, motion, robot, human=human, keyframes=keyframes, sections=sections)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path

"""The verdict table as text: one row per check (PASS / FAIL / -, key figure, worst frames),
then the reasons and the overall verdict. Returned as a string; the CLI prints it."""

from __future__ import annotations

from motion2robot.util.ranges import frame_ranges
from motion2robot.validate.reasons import human_name
from motion2robot.validate.report import CHECK_NAMES, FeasibilityReport


def _figure(name: str, c: dict) -> str:
    if c.get("skipped"):
        return f"skipped: {c['skipped']}"
    g = c.get
    if name == "joint_limits":
        return f"max excess {g('max_excess_rad', 0):.3f} rad"
    if name == "velocity_limits":
        return f"peak {g('max_rad_s', 0):.2f} rad/s ({g('max_ratio', 0):.2f} x limit)"
    if name == "acceleration":
        return f"peak {g('max_rad_s2', 0):.0f} rad/s^2 ({g('max_ratio', 0):.2f} x limit)"
    if name == "torque_limits":
        j = g("worst_joint")
        return f"peak {g('max_ratio', 0):.2f} x limit" + (f" ({human_name(j)})" if j else "")
    if name == "self_collision":
        return f"deepest {g('max_depth_m', 0) * 1000:.1f} mm"
    if name == "ground":
        return (f"penetration {g('max_penetration_m', 0) * 1000:.1f} mm, planted soles up to "
                f"{g('max_slip_m_s', 0) * 100:.1f} cm/s, slipping {len(g('slipping_frames', []))} frames, "
                f"skimming {len(g('skimming_frames', []))} frames")
    if name == "balance":
        zm, cm = g("min_zmp_margin_m"), g("min_com_margin_m")
        s = "ZMP margin " + ("n/a" if zm is None else f"{zm * 1000:+.0f} mm")
        s += ", CoM margin " + ("n/a" if cm is None else f"{cm * 1000:+.0f} mm")
        return s + (f", flight {len(g('flight_frames'))} frames" if g("flight_frames") else "")
    if name == "rollout":
        s = f"fell at {g('fall_time_s'):.2f} s ({g('fall_cause')})" if g("fell") else "stayed up"
        return s + f", tracking RMS {g('tracking_rms_mean_rad', 0):.3f} rad, {g('realtime_factor', 0):.0f}x real time"
    if name == "trajectory":
        s = f"root path error mean {g('mean_error_m', 0) * 100:.1f} cm, max {g('max_error_m', 0) * 100:.1f} cm"
        if g("control_mean_error_m") is not None:
            s += f"; requested path {g('control_mean_error_m') * 100:.1f} cm (max {g('control_max_error_m') * 100:.1f})"
        return s
    return ""


def verdict_table(report: FeasibilityReport) -> str:
    """Multi-line text: table, reasons, verdict."""
    rows = []
    for name in CHECK_NAMES:
        c = report.checks.get(name)
        if c is None:
            continue
        if c.get("skipped"):
            status = "-"
        elif name == "trajectory":
            status = "info"
        else:
            status = "PASS" if c["ok"] else "FAIL"
        frames = frame_ranges(c.get("frames", []), 3) if c.get("frames") else ""
        rows.append((name, status, _figure(name, c), frames))
    w = [max(len(r[i]) for r in rows + [("check", "verdict", "figure", "frames")]) for i in range(4)]
    line = lambda r: "  ".join(s.ljust(w[i]) for i, s in enumerate(r)).rstrip()
    out = [f"{report.robot}: {report.frames} frames at {report.fps:g} fps",
           line(("check", "verdict", "figure", "frames")), line(tuple("-" * x for x in w))]
    out += [line(r) for r in rows]
    if report.reasons:
        out.append("")
        out += [f"- {s}" for s in report.reasons]
    f = report.figures
    if f.get("tempo") is not None:
        out.append("")
        out.append(f"tempo x{f['tempo']:.2f}" + (f": {f['tempo_reason']}" if f.get("tempo_reason") else ""))
        if f.get("fallback"):
            out.append(f"legs: {f['fallback']['mode']}, {f['fallback']['why']} ({f['fallback'].get('what', '')})")
    out.append("")
    out.append("FEASIBLE" if report.feasible else f"INFEASIBLE ({', '.join(report.failed)})")
    return "\n".join(out)

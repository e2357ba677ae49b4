"""Every sentence the feasibility report says, in one place.

:func:`reasons` turns the check dicts into short human sentences such as "right knee beyond its
upper limit by 0.21 rad in frames 40-52 (from 2.00 s)"; :func:`human_name` makes joint and body
names readable ("r_knee" -> "right knee", "l_sho_pitch" -> "left shoulder pitch").
"""

from __future__ import annotations

from motion2robot.util.ranges import frame_ranges

#: Violations worded per check; the rest are summarised as "... and N more".
MAX_PER_CHECK = 3
#: rad; a playback tracking error above this is worth a sentence even when the robot stays up.
TRACKING_NOTE = 0.3

_WORDS = {
    "l": "left", "r": "right", "sho": "shoulder", "el": "elbow", "elb": "elbow", "ank": "ankle",
    "hip": "hip", "knee": "knee", "pan": "pan", "tilt": "tilt", "yaw": "yaw", "roll": "roll",
    "pitch": "pitch", "wr": "wrist", "neck": "neck", "body": "body",
}
_DROP = {"joint", "link", "jnt"}


def human_name(name: str) -> str:
    """'r_knee' -> 'right knee', 'left_knee_joint' -> 'left knee', 'l_el_link' -> 'left elbow'."""
    words = [w for w in name.replace("-", "_").split("_") if w and w.lower() not in _DROP]
    return " ".join(_WORDS.get(w.lower(), w.lower()) for w in words) or name


def _where(frames: list[int], fps: float) -> str:
    if not frames:
        return ""
    return f"in frames {frame_ranges(frames, 4)} (from {frames[0] / fps:.2f} s)"


def _more(items: list, what: str) -> list[str]:
    extra = len(items) - MAX_PER_CHECK
    return [f"... and {extra} more {what}"] if extra > 0 else []


def _joint_limits(c: dict, fps: float) -> list[str]:
    out = []
    for v in c.get("violations", [])[:MAX_PER_CHECK]:
        side = "upper" if v["value_rad"] > v["upper_rad"] else "lower"
        out.append(f"{human_name(v['joint'])} beyond its {side} limit by {v['by_rad']:.2f} rad {_where(v['frames'], fps)}")
    return out + _more(c.get("violations", []), "joints beyond their limits")


def _velocity(c: dict, fps: float) -> list[str]:
    out = [f"{human_name(v['joint'])} moves at {v['peak_rad_s']:.1f} rad/s, {v['ratio']:.1f}x its servo's "
           f"{v['limit_rad_s']:.1f} rad/s, {_where(v['frames'], fps)}" for v in c.get("violations", [])[:MAX_PER_CHECK]]
    return out + _more(c.get("violations", []), "joints too fast")


def _acceleration(c: dict, fps: float) -> list[str]:
    out = [f"{human_name(v['joint'])} accelerates at {v['peak_rad_s2']:.0f} rad/s^2, {v['ratio']:.1f}x the "
           f"{v['limit_rad_s2']:.0f} rad/s^2 its servo can reach, {_where(v['frames'], fps)}"
           for v in c.get("violations", [])[:MAX_PER_CHECK]]
    return out + _more(c.get("violations", []), "joints with acceleration spikes")


def _torque(c: dict, fps: float) -> list[str]:
    out = []
    for v in c.get("violations", [])[:MAX_PER_CHECK]:
        s = f"{human_name(v['joint'])} needs {v['peak_nm']:.2f} N*m, {v['ratio']:.1f}x its servo's {v['limit_nm']:.1f} N*m"
        if v.get("servo_nm", 0.0) > 0.5 * v["peak_nm"]:
            s += f" ({v['servo_nm']:.1f} N*m of it to move the servo's own rotor inertia and damping)"
        out.append(f"{s}, {_where(v['frames'], fps)}")
    return out + _more(c.get("violations", []), "joints over their torque limit")


def _self_collision(c: dict, fps: float) -> list[str]:
    out = []
    for v in c.get("violations", [])[:MAX_PER_CHECK]:
        pair = f"{human_name(v['body1'])} and {human_name(v['body2'])}"
        if "nominal_depth_m" in v:  # the model itself overlaps there: only the deepening counts
            out.append(f"{pair} (the model itself overlaps them {v['nominal_depth_m'] * 1000:.0f} mm in its nominal pose) "
                       f"go {v['depth_m'] * 1000:.0f} mm deeper, {_where(v['frames'], fps)}")
        else:
            out.append(f"{pair} collide, {v['depth_m'] * 1000:.0f} mm deep, {_where(v['frames'], fps)}")
    return out + _more(c.get("violations", []), "colliding body pairs")


def _ground(c: dict, fps: float) -> list[str]:
    pen = c.get("penetrations", [])
    out = [f"{human_name(v['body'])} goes {v['depth_m'] * 1000:.0f} mm below the floor {_where(v['frames'], fps)}"
           for v in pen[:MAX_PER_CHECK]] + _more(pen, "bodies below the floor")
    for v in c.get("slipping", []):
        what = "twists" if v["kind"] == "twist" else "slides"
        out.append(f"{v['foot']} sole {what} {_speed(v['speed_m_s'])} at its {v['point']} {_where(v['frames'], fps)} "
                   f"while planted (a planted sole must stay below {_speed(c.get('slip_speed_m_s', 0.0))})")
    for v in c.get("skimming", []):
        out.append(f"{v['foot']} foot skims the floor at {v['height_m'] * 1000:.0f} mm, moving {_speed(v['speed_m_s'])}, "
                   f"{_where(v['frames'], fps)} (a swing foot needs {c.get('swing_clearance_m', 0.0) * 1000:.0f} mm "
                   "of clearance: lift it)")
    return out


def _speed(v: float) -> str:
    return f"{v:.2f} m/s" if v >= 1.0 else f"{v * 100:.1f} cm/s"


def _distance(metres: float) -> str:
    return f"{metres:.1f} m" if metres >= 1.0 else f"{metres * 1000:.0f} mm"


def _balance(c: dict, fps: float, fall: str) -> list[str]:
    out = []
    for key, what in (("zmp", "the ZMP"), ("com", "CoM")):
        w = c.get(f"{key}_worst")
        if w:
            frames = c[f"{key}_outside_frames"]
            out.append(f"{what} leaves the support polygon at {frames[0] / fps:.2f} s (frames "
                       f"{frame_ranges(frames, 4)}), by up to {_distance(w['by_m'])} at {w['time_s']:.2f} s")
    slip = c.get("slip_worst")
    if slip:
        mu = "/".join(f"{v:g}" for v in slip["mu"])
        out.append(f"no friction-feasible contact forces {_where(c['slip_frames'], fps)}: the feet would slip, "
                   f"the floor (friction {mu}) falling short by up to {slip['force_n']:.1f} N and "
                   f"{slip['twist_nm']:.2f} N*m of twist")
    if c.get("flight_frames") and not c.get("ok", True):
        out.append(f"no sole touches the floor (flight) {_where(c['flight_frames'], fps)}")
    if out and fall:
        out[0] += f"; {fall}"
    return out


def _fall(c: dict | None) -> str:
    if not c or not c.get("fell"):
        return ""
    cause = "its torso sinks" if c.get("fall_cause") == "height" else "its torso tips over"
    return f"the robot falls at {c['fall_time_s']:.2f} s in playback ({cause})"


def _rollout(c: dict) -> list[str]:
    out = [_fall(c)] if c.get("fell") else []
    j = c.get("worst_tracking_joint")
    if j and c.get("tracking_max_rad", {}).get(j, 0.0) > TRACKING_NOTE:
        out.append(f"in playback the {human_name(j)} lags its target by up to {c['tracking_max_rad'][j]:.2f} rad")
    return out


def trajectory_sentence(c: dict) -> list[str]:
    out = []
    if c.get("control_mean_error_m") is not None:
        out.append(f"the root follows the requested trajectory ({c.get('control_source')}) within "
                   f"{c['control_mean_error_m'] * 100:.0f} cm on average (max {c['control_max_error_m'] * 100:.0f} cm; "
                   f"{c['control_mean_error_human_m'] * 100:.0f} cm at human scale)")
    if c.get("skipped") or c.get("mean_error_m") is None:
        return out
    s = f"the root path follows the human's within {c['mean_error_m'] * 100:.0f} cm on average (max {c['max_error_m'] * 100:.0f} cm)"
    if c.get("heading_error_mean_deg") is not None:
        s += f", heading off by {c['heading_error_mean_deg']:.0f} deg on average"
    return [s] + out


def reasons(checks: dict[str, dict], fps: float) -> list[str]:
    """Sentences for every failing check, in check order; the trajectory figure last."""
    out: list[str] = []
    word = {"joint_limits": _joint_limits, "velocity_limits": _velocity, "acceleration": _acceleration,
            "torque_limits": _torque, "self_collision": _self_collision, "ground": _ground}
    roll = checks.get("rollout")
    fall = _fall(roll) if roll and not roll.get("skipped") else ""
    for name, fn in word.items():
        c = checks.get(name)
        if c is not None and not c.get("ok", True):
            out += fn(c, fps)
    bal = checks.get("balance")
    balance_lines = _balance(bal, fps, fall) if bal is not None and not bal.get("ok", True) else []
    out += balance_lines
    if roll and not roll.get("skipped"):
        lines = _rollout(roll)
        if balance_lines and fall:
            lines = [s for s in lines if s != fall]
        out += lines
    if "trajectory" in checks:
        out += trajectory_sentence(checks["trajectory"])
    return out

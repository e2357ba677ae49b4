"""Render a drafted robot config (:class:`motion2robot.robot.draft.Draft`) as commented TOML.

A small writer for the few value types a config holds (strings, numbers, lists of numbers,
inline tables of those): the standard library reads TOML (``tomllib``) but does not write it,
and comments — which carry the CHECK notes — are not something general TOML writers emit.
"""

from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from motion2robot.robot.draft_types import Draft

_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def key(k: str) -> str:
    """A TOML key: bare when possible, else a quoted string."""
    return k if _BARE.match(k) else value(k)


def value(v: Any) -> str:
    """A TOML value for str, bool, int, float, list/tuple of those, or dict (inline table)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"cannot write non-finite number {v!r}")
        s = repr(round(v, 6) + 0.0)
        return s if any(c in s for c in ".en") else s + ".0"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{key(k)} = {value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def _string(s: str) -> str:
    """A TOML basic string: quotes, backslashes and control characters escaped."""
    out = []
    for ch in s:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def comment(text: str) -> list[str]:
    return [f"# {ln}".rstrip() for ln in text.splitlines()] if text else []


def render(draft: "Draft", mjcf_ref: str | None) -> str:
    """The config as TOML text; ``mjcf_ref`` is the MJCF path to write (relative to the TOML), or
    None to write the absolute path (menagerie drafts write ``menagerie`` + ``entry`` instead)."""
    out = comment(
        f"Robot config DRAFTED by 'motion2robot robots init {draft.model_ref}'.\n"
        "Every value was guessed from the model's kinematic tree and names; lines marked CHECK need a\n"
        "human look. Check it with 'motion2robot robots show THIS.toml'.")
    out += ["", f"name = {value(draft.name)}", f"description = {value('drafted from ' + draft.model_ref)}", "", "[model]"]
    if draft.menagerie:
        out += [f"menagerie = {value(draft.menagerie)}", f"entry = {value(draft.entry)}"]
    else:
        out += [f"mjcf = {value(mjcf_ref if mjcf_ref is not None else str(draft.mjcf.resolve()))}"]
    out += [f"root_body = {value(draft.root_body)}", f"torso_body = {value(draft.torso_body)}", ""]
    out += ["[defaults]", f"velocity = {value(draft.default_velocity)}  # CHECK: an MJCF has no velocity limits",
            f"torque = {value(draft.default_torque)}", f"kp = {value(draft.default_kp)}", ""]
    out += comment("Torque limits (N*m) from the model's actuators; kp (N*m/rad) from its position actuators,\n"
                   "else torque / 0.5 rad (full torque at 0.5 rad error).")
    for j in draft.joints:
        notes = [n for n in j.note.split("; ") if n.startswith("CHECK")]
        out += comment("\n".join(notes)) + [f"[joints.{key(j.name)}]"]
        if j.range is not None:
            out += [f"range = {value(list(j.range))}",
                    f"reason = {value('CHECK: drafted guess, the model declares no range')}"]
        out += [f"torque = {value(j.torque)}", f"kp = {value(j.kp)}"]
    out += ["", *comment("Nominal standing posture (rad; joints not listed are 0).\n"
                         "Knees bent and hip + knee + ankle pitch = 0 keep the pelvis upright and the soles flat."), "[nominal]"]
    out += [f"{key(k)} = {value(v)}" for k, v in draft.nominal.items()] + [""]
    out += comment("SMPL22 keypoint -> robot body + offset (m, body frame).") + ["[keypoints]"]
    for k in draft.keypoints:
        t: dict[str, Any] = {"body": k.body, "offset": list(k.offset)}
        if k.weight != 1.0:
            t["weight"] = k.weight
        out += comment(k.note) + [f"{key(k.human)} = {value(t)}"]
    for f in draft.feet:
        out += ["", *comment(f.note), f"[feet.{f.side}]", f"body = {value(f.body)}",
                f"sole_center = {value(list(f.sole_center))}", f"sole_half = {value(list(f.sole_half))}"]
        if f.sole_quat is not None:
            out += [f"sole_quat = {value(list(f.sole_quat))}"]
    return "\n".join(out) + "\n"

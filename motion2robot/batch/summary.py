"""Summaries of a results file: executable rate, failing checks, common reasons, slowest clips.

Reasons and errors carry clip-specific numbers ("left_knee 0.31 rad over its limit in frames
12-40"); to find the *common* ones they are grouped by :func:`pattern` (numbers, frame lists and
the clip's own path taken out); each group keeps one full example. Continuation lines of a
report ("... and 3 more joints ...") are not counted as reasons.
"""

from __future__ import annotations

import csv
import re
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Sequence

import numpy as np

_NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?", re.IGNORECASE)
_PARENS = re.compile(r"\s*\([^()]*(?:\([^()]*\)[^()]*)*\)")  # "(frames 3-7, ... (5 runs))"
_FRAMES = re.compile(r",?\s*\bin frames?\b[\s#\-,.]*")


def pattern(text: str, path: str | None = None) -> str:
    """Group key of a reason or error: the clip's path -> ``<file>``, parenthesised details and
    frame lists dropped, numbers -> ``#``."""
    if path:
        text = text.replace(path, "<file>")
    text = _FRAMES.sub(" ", _NUMBER.sub("#", _PARENS.sub("", text)))
    return " ".join(text.split())


@dataclass(frozen=True)
class Summary:
    """Counts over rows: clips = feasible + infeasible + errors. ``executable_rate`` is
    feasible / clips (errors count as not executable); ``solved_rate`` is feasible / (feasible +
    infeasible). ``failed_checks``: clips failing each check; ``reasons`` / ``errors``: (pattern,
    clips, example) most common first; ``slowest``: (key, total_s, frames) slowest first."""

    clips: int
    feasible: int
    infeasible: int
    errors: int
    frames: int
    executable_rate: float | None
    solved_rate: float | None
    failed_checks: tuple[tuple[str, int], ...]
    reasons: tuple[tuple[str, int, str], ...]
    error_kinds: tuple[tuple[str, int, str], ...]
    slowest: tuple[tuple[str, float, int | None], ...]
    time_s: dict[str, float]
    #: clips with a requested trajectory and the mean of their root errors (robot and human metres).
    control: dict[str, float] | None = None
    #: edit pairs: how many, executable source, executable edit, edits that break / fix a source.
    edits: dict[str, int] | None = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "clips": self.clips, "feasible": self.feasible, "infeasible": self.infeasible,
            "errors": self.errors, "frames": self.frames, "executable_rate": self.executable_rate,
            "solved_rate": self.solved_rate, "failed_checks": dict(self.failed_checks),
            "reasons": [{"pattern": p, "clips": n, "example": e} for p, n, e in self.reasons],
            "errors_by_kind": [{"pattern": p, "clips": n, "example": e} for p, n, e in self.error_kinds],
            "slowest": [{"key": k, "total_s": t, "frames": f} for k, t, f in self.slowest],
            "time_s": self.time_s, "control": self.control, "edits": self.edits,
        }


def _grouped(pairs: Iterable[tuple[str, str]], top: int) -> tuple[tuple[str, int, str], ...]:
    counts: Counter[str] = Counter()
    example: dict[str, str] = {}
    for pat, text in pairs:
        counts[pat] += 1
        example.setdefault(pat, text)
    return tuple((p, n, example[p]) for p, n in counts.most_common(top))


def summarize(rows: Sequence[dict[str, Any]], top: int = 10) -> Summary:
    """Summarise result rows (any subset of a results file)."""
    feasible = sum(1 for r in rows if not r.get("error") and r.get("feasible") is True)
    errors = sum(1 for r in rows if r.get("error"))
    infeasible = len(rows) - feasible - errors
    checks: Counter[str] = Counter()
    for r in rows:
        if not r.get("error"):
            checks.update(set(r.get("failed_checks") or ()))
    reasons = _grouped(((pattern(s, r.get("path")), s) for r in rows if not r.get("error")
                        for s in dict.fromkeys(r.get("reasons") or ()) if not s.startswith("...")), top)
    error_kinds = _grouped(((pattern(r["error"], r.get("path")), r["error"]) for r in rows if r.get("error")), top)
    timed = [r for r in rows if (r.get("timings") or {}).get("total_s") is not None]
    slowest = sorted(timed, key=lambda r: r["timings"]["total_s"], reverse=True)[:top]
    time_s = {stage: round(sum((r.get("timings") or {}).get(f"{stage}_s") or 0.0 for r in rows), 3)
              for stage in ("read", "retarget", "check", "total")}
    return Summary(
        clips=len(rows), feasible=feasible, infeasible=infeasible, errors=errors,
        frames=sum(int(r.get("frames") or 0) for r in rows),
        executable_rate=feasible / len(rows) if rows else None,
        solved_rate=feasible / (feasible + infeasible) if feasible + infeasible else None,
        failed_checks=tuple(sorted(checks.items(), key=lambda kv: (-kv[1], kv[0]))),
        reasons=reasons, error_kinds=error_kinds,
        slowest=tuple((r["key"], float(r["timings"]["total_s"]), r.get("frames")) for r in slowest),
        time_s=time_s, control=_control(rows), edits=_edits(rows),
    )


def _edits(rows: Sequence[dict[str, Any]]) -> dict[str, int] | None:
    e = [(r.get("feasible") is True, r["edit"].get("source_feasible") is True) for r in rows
         if not r.get("error") and isinstance(r.get("edit"), dict)]
    if not e:
        return None
    return {"pairs": len(e), "source_executable": sum(s for _, s in e), "edit_executable": sum(f for f, _ in e),
            "both_executable": sum(f and s for f, s in e), "edit_breaks": sum(s and not f for f, s in e),
            "edit_fixes": sum(f and not s for f, s in e)}


def _control(rows: Sequence[dict[str, Any]]) -> dict[str, float] | None:
    c = [r["control"] for r in rows if not r.get("error") and isinstance(r.get("control"), dict)
         and r["control"].get("control_mean_error_m") is not None]
    if not c:
        return None
    return {"clips": len(c), "mean_error_m": round(float(np.mean([x["control_mean_error_m"] for x in c])), 4),
            "mean_error_human_m": round(float(np.mean([x["control_mean_error_human_m"] for x in c])), 4),
            "max_error_m": round(float(max(x["control_max_error_m"] for x in c)), 4)}


def percent(x: float | None) -> str:
    return "n/a" if x is None else f"{100 * x:.1f}%"


def format_summary(s: Summary, robot: str | None = None) -> str:
    """The plain-text summary printed at the end of a batch and by ``batch-report``."""
    head = f"{s.clips} clips ({s.frames} frames)" + (f" on {robot}" if robot else "")
    lines = [
        head,
        f"  executable: {s.feasible} ({percent(s.executable_rate)}); not executable: {s.infeasible}; "
        f"errors (not read/solved): {s.errors}",
        f"  executable among solved clips: {percent(s.solved_rate)}",
        f"  CPU time: read {s.time_s['read']:.1f} s, retarget {s.time_s['retarget']:.1f} s, "
        f"check {s.time_s['check']:.1f} s",
    ]
    if s.edits:
        e = s.edits
        lines.append(f"  edit pairs: {e['pairs']}; the edit stays executable in {e['both_executable']} of "
                     f"{e['source_executable']} pairs whose source is executable "
                     f"({percent(e['both_executable'] / e['source_executable']) if e['source_executable'] else 'n/a'}); "
                     f"breaks {e['edit_breaks']}, fixes {e['edit_fixes']}")
    if s.control:
        lines.append(f"  requested trajectories ({s.control['clips']} clips): root error mean "
                     f"{s.control['mean_error_m'] * 100:.1f} cm on the robot ({s.control['mean_error_human_m'] * 100:.1f} cm "
                     f"at human scale), max {s.control['max_error_m'] * 100:.1f} cm")
    if s.failed_checks:
        lines.append("failing checks (clips):")
        lines += [f"  {name:<18} {n:>6}  ({percent(n / s.clips)})" for name, n in s.failed_checks]
    if s.reasons:
        lines.append("most common reasons (clips, e.g.):")
        lines += [f"  {n:>6}  {ex}" for _, n, ex in s.reasons]
    if s.error_kinds:
        lines.append("errors (clips, e.g.):")
        lines += [f"  {n:>6}  {ex}" for _, n, ex in s.error_kinds]
    if s.slowest:
        lines.append("slowest clips:")
        lines += [f"  {t:8.2f} s  {f if f is not None else '?':>5} frames  {k}" for k, t, f in s.slowest[:5]]
    return "\n".join(lines)


CSV_COLUMNS = ("key", "path", "clip", "frames", "fps", "duration_s", "prompt", "feasible", "failed_checks",
               "reasons", "error", "read_s", "retarget_s", "check_s", "total_s", "robot", "motion_file")


def flat_row(r: dict[str, Any]) -> dict[str, Any]:
    """One row as flat columns: lists joined (checks by ';', reasons by ' | '), timings and the
    scalar figures (prefixed ``fig_``) spread out."""
    out = {k: r.get(k) for k in CSV_COLUMNS}
    out["failed_checks"] = ";".join(r.get("failed_checks") or ())
    out["reasons"] = " | ".join(r.get("reasons") or ())
    for stage in ("read_s", "retarget_s", "check_s", "total_s"):
        out[stage] = (r.get("timings") or {}).get(stage)
    for k, v in (r.get("figures") or {}).items():
        if v is None or isinstance(v, (int, float, str, bool)):
            out[f"fig_{k}"] = v
    return out


def write_csv(rows: Sequence[dict[str, Any]], path: str | Path) -> Path:
    """One line per clip; columns :data:`CSV_COLUMNS` then every scalar figure seen."""
    flat = [flat_row(r) for r in rows]
    extra = sorted({k for f in flat for k in f} - set(CSV_COLUMNS))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=[*CSV_COLUMNS, *extra], restval="")
        w.writeheader()
        w.writerows(flat)
    return path

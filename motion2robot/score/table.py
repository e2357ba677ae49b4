"""The score table as text (stdout), Markdown, CSV and JSON: one row per set, the same columns."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any, Callable, Sequence

from motion2robot.score.figures import SetFigures


def _pct(x: float | None) -> str:
    return "n/a" if x is None else f"{100 * x:.1f}%"


def _num(x: float | None, fmt: str = ".2f", unit: str = "") -> str:
    return "n/a" if x is None else f"{x:{fmt}}{unit}"


def _tempo(f: SetFigures) -> str:
    return "n/a" if f.tempo_median is None else f"x{f.tempo_median:.2f} / x{f.tempo_p90:.2f}"


def _failures(f: SetFigures) -> str:
    return ", ".join(f"{c} {n}" for c, n in f.top_checks) or "-"


def _trajectory(f: SetFigures) -> str:
    return "-" if f.trajectory_error_m is None else f"{100 * f.trajectory_error_m:.1f} cm ({f.trajectory_samples})"


#: (header, cell text) of the table's columns, in order.
COLUMNS: tuple[tuple[str, Callable[[SetFigures], str]], ...] = (
    ("set", lambda f: f.name),
    ("samples", lambda f: str(f.samples)),
    ("executable", lambda f: f"{_pct(f.executable_share)} ({f.executable})"),
    ("tempo median / p90", _tempo),
    ("fallback", lambda f: _pct(f.fallback_share)),
    ("keypoint error path / pose", lambda f: f"{_num(f.keypoint_error_cm, '.1f')} / {_num(f.keypoint_error_pose_cm, '.1f')} cm"),
    ("contact agreement", lambda f: _pct(f.contact_agreement)),
    ("trajectory error", _trajectory),
    ("errors", lambda f: str(f.errors)),
    ("main failures (samples)", _failures),
    ("samples/min/core", lambda f: _num(f.samples_per_min_per_core, ".1f")),
)


def cells(figures: Sequence[SetFigures]) -> list[list[str]]:
    return [[cell(f) for _, cell in COLUMNS] for f in figures]


def format_table(figures: Sequence[SetFigures], robot: str) -> str:
    """The plain-text table printed on stdout, with the legend of its columns."""
    head = [h for h, _ in COLUMNS]
    body = cells(figures)
    width = [max(len(r[i]) for r in [head, *body]) for i in range(len(head))]
    line = lambda r: "  ".join(c.ljust(w) if i in (0, 9) else c.rjust(w) for i, (c, w) in enumerate(zip(r, width)))  # noqa: E731
    out = [f"score on {robot}", line(head), "  ".join("-" * w for w in width)] + [line(r) for r in body]
    out += [legend(robot)]
    for f in figures:
        if f.top_reason:
            out.append(f"{f.name}: most common reason ({f.top_reason[1]} samples): {f.top_reason[0]}")
    return "\n".join(out)


def legend(robot: str) -> str:
    return (f"executable: passes every check on {robot}, physics playback included unless --no-physics; tempo: "
            "slow-down the executable samples needed (x1.00 = as generated); fallback: the legs on an alternative "
            "(steps: the robot's own walking pattern of the human's footsteps; stance: a fixed stance); "
            "keypoint error: robot vs the human scaled to the robot, mean over frames and keypoints, in the world "
            "(path) and pelvis on pelvis (pose); contact "
            "agreement: (frame, foot) pairs where the robot's foot contact matches the human's labels")


def markdown(figures: Sequence[SetFigures], robot: str) -> str:
    """A paste-ready Markdown table with a one-line caption."""
    def esc(c: str) -> str:
        return c.replace("|", "\\|")

    head = [h for h, _ in COLUMNS]
    rows = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    rows += ["| " + " | ".join(esc(c) for c in r) + " |" for r in cells(figures)]
    return f"Executability on **{robot}** (motion2robot score)\n\n" + "\n".join(rows) + f"\n\n{legend(robot)}\n"


def write_csv(figures: Sequence[SetFigures], path: str | Path) -> Path:
    """One line per set with the raw figures (shares as fractions, lengths in the units of the
    field names); ``top_checks`` as ``check:samples;...``."""
    path = Path(path)
    dicts = [f.to_dict() for f in figures]
    for d in dicts:
        d["top_checks"] = ";".join(f"{k}:{v}" for k, v in d["top_checks"].items())
        d["top_reason"] = d["top_reason"]["example"] if d["top_reason"] else ""
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(dicts[0]) if dicts else [])
        w.writeheader()
        w.writerows(dicts)
    return path


def to_json(figures: Sequence[SetFigures], robot: str, extra: dict[str, Any] | None = None) -> str:
    return json.dumps({"robot": robot, "sets": [f.to_dict() for f in figures], **(extra or {})}, indent=1)

"""A self-contained HTML page of a results file: the summary, then one table row per clip
(no scripts, no external files; every value escaped)."""

from __future__ import annotations

from html import escape
from pathlib import Path
from typing import Any, Sequence

from motion2robot.batch.summary import Summary, percent

_STYLE = """
body{font-family:sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse;margin:0.5em 0 1.5em}
td,th{border:1px solid #ccc;padding:2px 6px;font-size:13px;vertical-align:top;text-align:left}
th{background:#f0f0f0}
tr.ok td.status{background:#d8f5d8} tr.fail td.status{background:#fde2c8} tr.error td.status{background:#f8c8c8}
td.num{text-align:right;font-variant-numeric:tabular-nums}
"""


def _table(header: Sequence[str], rows: Sequence[Sequence[Any]], classes: Sequence[str] | None = None) -> str:
    out = ["<table><tr>" + "".join(f"<th>{escape(h)}</th>" for h in header) + "</tr>"]
    for i, r in enumerate(rows):
        cls = f' class="{classes[i]}"' if classes else ""
        cells = []
        for v in r:
            if isinstance(v, tuple):  # (text, css class)
                cells.append(f'<td class="{v[1]}">{escape(str(v[0]))}</td>')
            elif isinstance(v, (int, float)) and not isinstance(v, bool):
                cells.append(f'<td class="num">{escape(str(v))}</td>')
            else:
                cells.append(f"<td>{escape('' if v is None else str(v))}</td>")
        out.append(f"<tr{cls}>" + "".join(cells) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def _status(r: dict[str, Any]) -> str:
    if r.get("error"):
        return "error"
    return "ok" if r.get("feasible") else "fail"


def render_html(rows: Sequence[dict[str, Any]], s: Summary, title: str) -> str:
    """The page as a string."""
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{escape(title)}</title>",
             f"<style>{_STYLE}</style></head><body><h1>{escape(title)}</h1>"]
    parts.append(_table(["clips", "frames", "executable", "not executable", "errors", "executable rate",
                         "executable among solved"],
                        [[s.clips, s.frames, s.feasible, s.infeasible, s.errors, percent(s.executable_rate),
                          percent(s.solved_rate)]]))
    if s.failed_checks:
        parts.append("<h2>Failing checks</h2>")
        parts.append(_table(["check", "clips", "share"], [[c, n, percent(n / s.clips)] for c, n in s.failed_checks]))
    if s.reasons:
        parts.append("<h2>Most common reasons</h2>")
        parts.append(_table(["clips", "example"], [[n, ex] for _, n, ex in s.reasons]))
    if s.error_kinds:
        parts.append("<h2>Errors</h2>")
        parts.append(_table(["clips", "example"], [[n, ex] for _, n, ex in s.error_kinds]))
    parts.append("<h2>Clips</h2>")
    body = []
    for r in rows:
        t = r.get("timings") or {}
        status = _status(r)
        body.append([r.get("path"), r.get("clip"), r.get("frames"), (status, "status"),
                     ", ".join(r.get("failed_checks") or ()),
                     r.get("error") or "; ".join(r.get("reasons") or ()), r.get("prompt"), t.get("total_s")])
    parts.append(_table(["file", "clip", "frames", "status", "failed checks", "reasons / error", "prompt",
                         "time (s)"], body, [_status(r) for r in rows]))
    parts.append("</body></html>")
    return "\n".join(parts)


def write_html(rows: Sequence[dict[str, Any]], s: Summary, path: str | Path, title: str = "motion2robot batch") -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(render_html(rows, s, title), encoding="utf-8")
    return path

"""A self-contained HTML page of a score run: the table, two plots (executable share per set, the
distribution of tempo factors) and, per set, the failing checks and common reasons (inline CSS,
PNG data URIs, every value escaped; the style of :mod:`motion2robot.batch.report_html`)."""

from __future__ import annotations

import base64
from html import escape
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from matplotlib.figure import Figure

from motion2robot.batch.report_html import _STYLE, _table
from motion2robot.batch.summary import Summary, percent
from motion2robot.score.figures import SetFigures
from motion2robot.score.table import COLUMNS, cells, legend
from motion2robot.viz.plots import figure_png


def _img(png: bytes, alt: str) -> str:
    return f'<img src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}" alt="{escape(alt)}">'


def plot_executable(figures: Sequence[SetFigures]) -> Figure:
    """Horizontal bars: executable / not executable / error share of each set."""
    fig = Figure(figsize=(8.0, 0.6 + 0.45 * len(figures)), layout="constrained")
    ax = fig.subplots()
    names = [f.name for f in figures][::-1]
    parts = [("executable", "#4caf50", lambda f: f.executable), ("not executable", "#ff9800", lambda f: f.not_executable),
             ("error", "#e53935", lambda f: f.errors)]
    left = np.zeros(len(figures))
    for label, color, get in parts:
        share = np.array([get(f) / f.samples if f.samples else 0.0 for f in figures][::-1])
        ax.barh(names, 100 * share, left=100 * left, color=color, label=label)
        left += share
    for y, f in enumerate(figures[::-1]):
        if f.executable_share is not None:
            ax.text(1, y, f"{100 * f.executable_share:.1f}% executable", va="center", fontsize=8)
    ax.set_xlim(0, 100)
    ax.set_xlabel("share of samples (%)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    return fig


def plot_tempo(tempos: dict[str, list[float]]) -> Figure:
    """Per set, the cumulative share of its executable samples needing at most each tempo factor."""
    fig = Figure(figsize=(8.0, 3.2), layout="constrained")
    ax = fig.subplots()
    for name, ts in tempos.items():
        if not ts:
            continue
        x = np.sort(ts)
        ax.step(np.concatenate([[1.0], x]), np.concatenate([[0.0], np.arange(1, len(x) + 1) / len(x)]) * 100,
                where="post", label=f"{name} ({len(x)})")
    ax.set_xlabel("tempo factor (x1 = as generated; higher = slowed)")
    ax.set_ylabel("executable samples (%)")
    ax.set_ylim(0, 102)
    if any(tempos.values()):
        ax.legend(fontsize=8)
    else:
        ax.text(0.5, 0.5, "no executable samples", transform=ax.transAxes, ha="center")
    ax.grid(alpha=0.3)
    return fig


def tempos_of(rows: Sequence[dict[str, Any]]) -> list[float]:
    """Tempo factors of the executable samples among ``rows``."""
    return [float((r.get("figures") or {}).get("tempo", 1.0)) for r in rows
            if not r.get("error") and r.get("feasible") is True]


def render_html(figures: Sequence[SetFigures], summaries: Sequence[Summary], tempos: dict[str, list[float]],
                robot: str, title: str) -> str:
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{escape(title)}</title>",
             f"<style>{_STYLE}</style></head><body><h1>{escape(title)}</h1>"]
    parts.append(_table([h for h, _ in COLUMNS], cells(figures)))
    parts.append(f"<p>{escape(legend(robot))}</p>")
    parts.append(_img(figure_png(plot_executable(figures)), "executable share per set"))
    parts.append(_img(figure_png(plot_tempo(tempos)), "tempo factors of the executable samples"))
    for f, s in zip(figures, summaries):
        parts.append(f"<h2>{escape(f.name)}</h2>")
        if s.failed_checks:
            parts.append(_table(["check", "samples", "share"], [[c, n, percent(n / s.clips)] for c, n in s.failed_checks]))
        if s.reasons:
            parts.append(_table(["samples", "most common reasons (e.g.)"], [[n, ex] for _, n, ex in s.reasons]))
        if s.error_kinds:
            parts.append(_table(["samples", "errors (e.g.)"], [[n, ex] for _, n, ex in s.error_kinds]))
    parts.append("</body></html>")
    return "\n".join(parts)


def write_html(path: str | Path, *args: Any, **kwargs: Any) -> Path:
    """:func:`render_html` written to ``path``."""
    path = Path(path)
    path.write_text(render_html(*args, **kwargs), encoding="utf-8")
    return path

"""Run a score: plan every set on its results file, process the new samples once through one
worker pool (``batch``'s backends and job), then compute each set's figures from its file and
write the table files."""

from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

from motion2robot.batch.results import ResultWriter, batch_lock, read_rows
from motion2robot.batch.run import run_items
from motion2robot.batch.summary import Summary, summarize
from motion2robot.batch.worker import BatchConfig
from motion2robot.errors import UserError
from motion2robot.score.figures import SetFigures, set_figures
from motion2robot.score.report_html import tempos_of, write_html
from motion2robot.score.sets import ScoreSet, plan_sets, set_names, union_todo
from motion2robot.score.table import markdown, to_json, write_csv


@dataclass(frozen=True)
class ScoreRun:
    """sets: the plans; figures / summaries: per set, in input order; processed: samples processed
    in this run (the others were already in the results files); wall_s: wall time of the
    processing."""

    robot: str
    sets: tuple[ScoreSet, ...]
    figures: tuple[SetFigures, ...]
    summaries: tuple[Summary, ...]
    tempos: dict[str, list[float]]
    processed: int
    wall_s: float


def set_rows(s: ScoreSet) -> list[dict[str, Any]]:
    """The rows of the set's samples in its results file (other keys in the file are ignored)."""
    keys = s.plan.keys
    return [r for r in read_rows(s.results).rows if r["key"] in keys]


def run_score(inputs: Sequence[str], out: str | Path, config: BatchConfig, *, redo: bool = False,
              read_options: Mapping[str, Any] | None = None, backend: str = "local", jobs: int = 2,
              ray_address: str | None = None, on_plan: Callable[[list[ScoreSet], int], None] | None = None,
              on_row: Callable[[dict], None] | None = None) -> ScoreRun:
    """Score ``inputs`` (see :mod:`~motion2robot.score.sets`) into the folder ``out``.
    ``on_plan(sets, todo)`` is called once planned, ``on_row(row)`` per row as it arrives."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise UserError(f"{out}: --out must be a folder (it holds one results file per set and the score files)")
    out.mkdir(parents=True, exist_ok=True)
    with contextlib.ExitStack() as stack:
        for name, _ in set_names(inputs):  # locked before planning, like batch: a second run fails at once
            stack.enter_context(batch_lock(out / f"{name}.jsonl"))
        sets = plan_sets(inputs, out, robot=config.robot, redo=redo, read_options=read_options)
        items, wants, errors = union_todo(sets)
        if on_plan:
            on_plan(sets, len(items))
        writers = {s.name: stack.enter_context(ResultWriter(s.results)) for s in sets if s.plan.todo}

        def write(row: dict) -> None:
            for s in wants[row["key"]]:
                writers[s.name].write(row)
            if on_row:
                on_row(row)

        t0 = time.perf_counter()
        processed = run_items(items, errors, config, write, backend=backend, jobs=jobs, ray_address=ray_address)
        wall = time.perf_counter() - t0
    rows = [set_rows(s) for s in sets]
    summaries = tuple(summarize(r) for r in rows)
    figures = tuple(set_figures(s.name, r, sm) for s, r, sm in zip(sets, rows, summaries))
    return ScoreRun(config.robot, tuple(sets), figures, summaries, {s.name: tempos_of(r) for s, r in zip(sets, rows)},
                    processed, wall)


def write_outputs(run: ScoreRun, out: str | Path) -> list[Path]:
    """``score.csv``, ``score.json``, ``score.md`` and ``score.html`` in ``out``."""
    out = Path(out)
    extra = {"inputs": {s.name: s.path for s in run.sets}, "results": {s.name: str(s.results) for s in run.sets}}
    md = out / "score.md"
    md.write_text(markdown(run.figures, run.robot), encoding="utf-8")
    js = out / "score.json"
    js.write_text(to_json(run.figures, run.robot, extra), encoding="utf-8")
    return [write_csv(run.figures, out / "score.csv"), js, md,
            write_html(out / "score.html", run.figures, run.summaries, run.tempos, run.robot,
                       title=f"motion2robot score on {run.robot}")]

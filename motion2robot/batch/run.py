"""Plan and run a batch: expand INPUTS, skip clips already in the results file, stream the rest
through a backend and append each row as it arrives."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

from motion2robot.batch.results import ResultWriter, read_rows, rewrite_without
from motion2robot.batch.work import Expansion, WorkItem, expand_inputs
from motion2robot.batch.worker import BatchConfig, base_row
from motion2robot.errors import UserError

BACKENDS = ("local", "ray")


@dataclass(frozen=True)
class BatchPlan:
    """expansion: every clip of the INPUTS; todo: the clips to process now; done: how many were
    already in the results file (resume); dropped: rows removed for ``--redo``; bad_lines:
    unparsable lines found in the existing file (a torn last line is normal after a crash)."""

    out: Path
    expansion: Expansion
    todo: tuple[WorkItem, ...]
    done: int
    dropped: int
    bad_lines: tuple[int, ...]

    @property
    def keys(self) -> set[str]:
        return {i.key for i in self.expansion.items}


def plan_batch(inputs: Sequence[str | Path], out: str | Path, *, redo: bool = False,
               redo_errors: bool = False, read_options: Mapping[str, Any] | None = None,
               robot: str | None = None, expansion: Expansion | None = None) -> BatchPlan:
    """Work out what to do. ``redo`` drops the existing rows of these clips (other rows in the
    file are kept); ``redo_errors`` drops only the rows that have an error. With ``robot``, a
    file whose rows for these clips were made for another robot is refused (resume would
    otherwise keep the other robot's verdicts). ``expansion``: the work items, when the caller
    expanded the INPUTS itself (edit pairs)."""
    out = Path(out)
    expansion = expansion or expand_inputs(inputs, read_options)
    keys = {i.key for i in expansion.items}
    existing = read_rows(out)
    dropped = 0
    if redo or redo_errors:
        drop = keys if redo else {r["key"] for r in existing.rows if r.get("error") and r["key"] in keys}
        if drop & existing.keys or existing.bad_lines:
            dropped = rewrite_without(out, drop)
        existing = read_rows(out)
    done_keys = existing.keys & keys
    if robot is not None:
        others = sorted({str(r.get("robot")) for r in existing.rows if r["key"] in done_keys} - {robot})
        if others:
            raise UserError(f"{out}: holds results of these clips for robot {', '.join(others)}, not {robot}; "
                            "give a different --out (or --redo to replace them)")
    todo = tuple(i for i in expansion.items if i.key not in done_keys)
    return BatchPlan(out, expansion, todo, len(done_keys), dropped, existing.bad_lines)


def run_plan(plan: BatchPlan, config: BatchConfig, *, backend: str = "local", jobs: int = 2,
             ray_address: str | None = None, on_row: Callable[[dict], None] | None = None,
             max_tasks_per_child: int | None = None) -> int:
    """Process ``plan.todo``, appending one fsync-ed row per clip to ``plan.out`` as it finishes.
    Files that could not be counted get their error row from the driver. Returns rows written."""
    if backend not in BACKENDS:
        raise UserError(f"unknown backend {backend!r}; use one of: {', '.join(BACKENDS)}")
    with ResultWriter(plan.out) as writer:
        def write(row: dict) -> None:
            writer.write(row)
            if on_row:
                on_row(row)

        return run_items(plan.todo, plan.expansion.count_errors, config, write, backend=backend, jobs=jobs,
                         ray_address=ray_address, max_tasks_per_child=max_tasks_per_child)


def run_items(items: Sequence[WorkItem], count_errors: Mapping[str, str], config: BatchConfig,
              write: Callable[[dict], None], *, backend: str = "local", jobs: int = 2,
              ray_address: str | None = None, max_tasks_per_child: int | None = None) -> int:
    """Process ``items`` through a backend, calling ``write(row)`` for each row as it arrives (the
    caller appends it to its results file(s)); items of uncountable files (``clip`` None) get
    their error row (``count_errors[path]``) from the driver. Returns rows written."""
    if backend not in BACKENDS:
        raise UserError(f"unknown backend {backend!r}; use one of: {', '.join(BACKENDS)}")
    written = 0
    for item in (i for i in items if i.clip is None):
        row = base_row(item, config)
        row["error"] = f"read: {count_errors.get(item.path, 'cannot read the file')}"
        write(row)
        written += 1
    work = [i for i in items if i.clip is not None]
    if not work:
        return written
    if backend == "ray":
        from motion2robot.batch.ray_backend import run_ray

        rows = run_ray(work, config, jobs, address=ray_address)
    else:
        from motion2robot.batch.local import run_local

        rows = run_local(work, config, jobs, max_tasks_per_child=max_tasks_per_child)
    try:
        for row in rows:
            write(row)
            written += 1
    finally:
        rows.close()
    return written

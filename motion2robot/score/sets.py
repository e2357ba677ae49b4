"""The sets of a score run: one per INPUT, each with its own batch results file.

An INPUT is ``NAME=PATH`` or ``PATH`` (a motion file, a folder or a manifest, as for ``batch``);
without a name the set is named after the path (its file stem or folder name). Each set's rows
live in ``OUT/<NAME>.jsonl``, an ordinary ``batch`` results file: ``batch-report`` reads it, and
a rerun processes only the samples not in it yet. A sample in several sets is processed once and
its row written to each set's file.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

from motion2robot.batch.run import BatchPlan, plan_batch
from motion2robot.batch.work import WorkItem
from motion2robot.errors import UserError

_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._+-]*$")


@dataclass(frozen=True)
class ScoreSet:
    """name: the set's label (a row of the table); path: its INPUT; plan: the batch plan of its
    results file ``results``."""

    name: str
    path: str
    plan: BatchPlan

    @property
    def results(self) -> Path:
        return self.plan.out


def parse_input(spec: str) -> tuple[str, str]:
    """(name, path) of ``NAME=PATH`` or ``PATH`` (an existing path containing '=' stays a path)."""
    if "=" in spec and not Path(spec).exists():
        name, path = spec.split("=", 1)
        if not _NAME.match(name):
            raise UserError(f"{spec}: set name {name!r} must be letters, digits, '.', '_', '+' or '-' "
                            "(it names the results file); e.g. mdm=samples/")
        if not path:
            raise UserError(f"{spec}: no path after '='; give NAME=PATH")
        return name, path
    p = Path(spec.rstrip("/")).expanduser()
    name = re.sub(r"[^A-Za-z0-9._+-]", "_", p.stem if p.suffix else p.name) or "set"
    return name.lstrip("._-") or "set", spec


def set_names(inputs: Sequence[str]) -> list[tuple[str, str]]:
    """(name, path) of every INPUT; UserError when there are none or two make the same name."""
    if not inputs:
        raise UserError("no INPUTS given; pass folders, files or manifests of generated samples (NAME=PATH to name a set)")
    parsed = [parse_input(s) for s in inputs]
    names = [n for n, _ in parsed]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise UserError(f"two INPUTS make the set {dup[0]!r}; name them apart with NAME=PATH (e.g. a={dup[0]} b=...)")
    return parsed


def plan_sets(inputs: Sequence[str], out: str | Path, *, robot: str, redo: bool = False,
              read_options: Mapping[str, Any] | None = None) -> list[ScoreSet]:
    """One plan per INPUT (see the module text); UserError for duplicate names or a results file
    that holds another robot's rows."""
    parsed = set_names(inputs)
    out = Path(out)
    return [ScoreSet(name, path, plan_batch([path], out / f"{name}.jsonl", redo=redo, read_options=read_options,
                                            robot=robot)) for name, path in parsed]


def union_todo(sets: Sequence[ScoreSet]) -> tuple[list[WorkItem], dict[str, list[ScoreSet]], dict[str, str]]:
    """The samples to process once each (input order), the sets whose file needs each key, and
    the count errors of uncountable files."""
    items: list[WorkItem] = []
    wants: dict[str, list[ScoreSet]] = {}
    errors: dict[str, str] = {}
    for s in sets:
        errors.update(s.plan.expansion.count_errors)
        for item in s.plan.todo:
            if item.key not in wants:
                items.append(item)
                wants[item.key] = []
            wants[item.key].append(s)
    return items, wants, errors

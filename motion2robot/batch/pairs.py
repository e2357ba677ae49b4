"""Batch work items of edit pairs (``batch --pairs``): one item per (source, edit) pair.

An INPUT is an editor result file (a MotionFix/OmniME result holding the edit and its source), a
folder searched recursively for them, or a manifest (``.txt`` / ``.lst``) whose lines hold a
source and an edit path separated by a tab (or by whitespace when neither path has spaces),
relative to the manifest. A pair item's path is ``SOURCE<TAB>EDIT``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

from motion2robot.batch.work import MANIFEST_EXTENSIONS, Expansion, WorkItem
from motion2robot.errors import UserError

SEPARATOR = "\t"


def _is_edit_result(path: Path) -> bool:
    try:
        from motion2robot.motion.read import detect_format

        return detect_format(path) == "edit_result"
    except UserError:
        return False


def _manifest_pairs(path: Path) -> list[tuple[Path, Path]]:
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as err:
        raise UserError(f"{path}: cannot read the pair manifest ({err}); give one 'SOURCE<TAB>EDIT' per line") from err
    out = []
    for n, line in enumerate(lines, 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        parts = line.split(SEPARATOR) if SEPARATOR in line else line.split()
        if len(parts) != 2:
            raise UserError(f"{path}: line {n} is not a pair ({line[:60]!r}); write SOURCE<TAB>EDIT")
        out.append(tuple(p if Path(p).is_absolute() else path.parent / p for p in map(Path, parts)))  # type: ignore[misc]
    return out


def expand_pairs(inputs: Sequence[str | Path]) -> Expansion:
    """Pairs of the INPUTS, in order, duplicates removed; files that are no editor result are
    listed as skipped."""
    if not inputs:
        raise UserError("no INPUTS given; pass editor result files, folders or a pair manifest")
    items: list[WorkItem] = []
    skipped: list[tuple[str, str]] = []
    seen: set[str] = set()

    def add(path: str) -> None:
        if path not in seen:
            seen.add(path)
            items.append(WorkItem(path, 0))

    for raw in inputs:
        p = Path(raw).expanduser()
        if not p.exists():
            raise UserError(f"{p}: no such file or folder; check the path")
        if p.is_dir():
            for f in sorted(q for q in p.rglob("*.npy") if q.is_file()):
                if _is_edit_result(f):
                    add(str(f.resolve()))
                else:
                    skipped.append((str(f.resolve()), "not an editor result (source and edit) file"))
        elif p.suffix.lower() in MANIFEST_EXTENSIONS:
            for src, edit in _manifest_pairs(p):
                add(f"{src.resolve()}{SEPARATOR}{edit.resolve()}")
        else:
            add(str(p.resolve()))
    return Expansion(tuple(items), tuple(skipped))

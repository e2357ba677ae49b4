"""The results file: JSON Lines, one row per clip, append-only and crash-safe.

Each row is written as one line, then flushed and ``os.fsync``-ed, so a crash (even SIGKILL or a
power cut) loses at most the clips still in flight. A crash in the middle of a write can leave a
torn last line without its newline: :func:`read_rows` ignores it, and :class:`ResultWriter` cuts
it off before appending, so the file always parses and that clip is simply done again.

Row schema: see :mod:`motion2robot.batch` (all keys always present):
``key, path, clip, frames, fps, duration_s, prompt, feasible, failed_checks, reasons, figures,
timings {read_s, retarget_s, check_s, total_s, cpu_s}, error, robot, version, motion_file,
worker {pid, max_rss_mb}, warnings, fidelity``.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

from motion2robot.errors import InputFileError, UserError
from motion2robot.util.jsonable import plain

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows: no advisory lock
    fcntl = None  # type: ignore[assignment]


def dumps_row(row: dict[str, Any]) -> str:
    """One JSON line (no newline) with numpy values converted and NaN/inf as null. A row holding
    a file name that is not UTF-8 (Python keeps its bytes as lone surrogates) is written with
    ASCII escapes (``\\udce9``): valid JSON and UTF-8, read back to the same name."""
    data = plain(row, fallback_str=True)
    text = json.dumps(data, ensure_ascii=False, separators=(",", ":"), allow_nan=False)
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        text = json.dumps(data, ensure_ascii=True, separators=(",", ":"), allow_nan=False)
    return text


def _lock_or_refuse(fh: Any, results: Path) -> None:
    """An exclusive, non-blocking flock on ``fh``; UserError (and ``fh`` closed) if another batch
    holds it."""
    if fcntl is None:
        return
    try:
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        fh.close()
        raise UserError(f"{results}: another batch is writing to this file; wait for it to end "
                        "or give a different --out") from None


class batch_lock:
    """Context manager: an exclusive lock on ``OUT.lock`` beside the results file, held for a whole
    batch (plan, ``--redo`` rewrite, run), so that a second batch on the same file fails at once
    before it reads or rewrites anything (the rewrite replaces the file, so a lock on the file
    itself would not cover it)."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.lock_path = self.path.with_name(self.path.name + ".lock")
        self._fh: Any = None

    def __enter__(self) -> "batch_lock":
        self.lock_path.parent.mkdir(parents=True, exist_ok=True)
        self._fh = open(self.lock_path, "a")  # noqa: SIM115 (closed in __exit__)
        _lock_or_refuse(self._fh, self.path)
        return self

    def __exit__(self, *exc: object) -> None:
        if self._fh is not None:
            self._fh.close()  # releases the lock; the empty lock file stays (removing it would race)


@dataclass(frozen=True)
class ReadResult:
    """rows: the parsed rows in file order (a key seen twice keeps its LAST row); bad_lines:
    1-based numbers of lines that did not parse (a torn last line after a crash)."""

    rows: tuple[dict[str, Any], ...]
    bad_lines: tuple[int, ...]

    @property
    def keys(self) -> set[str]:
        return {r["key"] for r in self.rows}


def read_rows(path: str | Path) -> ReadResult:
    """Read a results file, tolerating unparsable lines (reported, not raised)."""
    path = Path(path)
    if not path.exists():
        return ReadResult((), ())
    if path.is_dir():
        raise InputFileError(f"{path}: is a folder, not a results file; give a .jsonl path")
    by_key: dict[str, dict[str, Any]] = {}
    bad: list[int] = []
    with open(path, "rb") as fh:
        for n, raw in enumerate(fh, start=1):
            if not raw.strip():
                continue
            try:
                row = json.loads(raw)
            except (UnicodeDecodeError, json.JSONDecodeError):
                bad.append(n)
                continue
            if not isinstance(row, dict) or "key" not in row:
                bad.append(n)
                continue
            by_key.pop(row["key"], None)  # keep the last row, at its last position
            by_key[row["key"]] = row
    return ReadResult(tuple(by_key.values()), tuple(bad))


def _cut_torn_tail(path: Path) -> int:
    """Truncate an unterminated last line (a write interrupted by a crash); returns bytes cut."""
    size = path.stat().st_size
    if size == 0:
        return 0
    with open(path, "rb+") as fh:
        fh.seek(size - 1)
        if fh.read(1) == b"\n":
            return 0
        block = 1 << 16
        pos = size
        while pos > 0:  # find the last newline
            start = max(0, pos - block)
            fh.seek(start)
            chunk = fh.read(pos - start)
            i = chunk.rfind(b"\n")
            if i >= 0:
                keep = start + i + 1
                break
            pos = start
        else:
            keep = 0
        fh.truncate(keep)
        fh.flush()
        os.fsync(fh.fileno())
        return size - keep


def rewrite_without(path: str | Path, drop_keys: set[str]) -> int:
    """Atomically rewrite the file without the rows whose key is in ``drop_keys`` (used by
    ``--redo``); unparsable lines are dropped too. Returns the number of rows dropped."""
    path = Path(path)
    result = read_rows(path)
    kept = [r for r in result.rows if r["key"] not in drop_keys]
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w", encoding="utf-8") as fh:
        for r in kept:
            fh.write(dumps_row(r) + "\n")
        fh.flush()
        os.fsync(fh.fileno())
    tmp.replace(path)
    return len(result.rows) - len(kept)


class ResultWriter:
    """Append rows to a JSONL file, one fsync-ed line each. Use as a context manager.

    Holds an exclusive advisory lock (``flock``) on the file while open, so a second batch
    writing to the same file fails at once instead of interleaving duplicate rows."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        if self.path.is_dir():
            raise InputFileError(f"{self.path}: is a folder; give --out a .jsonl file path")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._fh = open(self.path, "a", encoding="utf-8")
        _lock_or_refuse(self._fh, self.path)
        self.torn_bytes = _cut_torn_tail(self.path)

    def write(self, row: dict[str, Any]) -> None:
        self._fh.write(dumps_row(row) + "\n")
        self._fh.flush()
        os.fsync(self._fh.fileno())

    def write_all(self, rows: Iterable[dict[str, Any]]) -> None:
        for r in rows:
            self.write(r)

    def close(self) -> None:
        if not self._fh.closed:
            self._fh.close()

    def __enter__(self) -> "ResultWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

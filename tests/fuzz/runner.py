"""Run one corpus case through ``motion2robot.cli.main`` in this process and judge it: a user
error must be exit code 2 and exactly one stderr line ``motion2robot: error: ...`` (warnings
printed before it count as extra lines), within a time limit."""

from __future__ import annotations

import io
import signal
import warnings
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass
from pathlib import Path

from motion2robot.cli import main
from tests.fuzz.corpus import Case


class CaseTimeout(BaseException):
    """Raised by the alarm: not an Exception, so the CLI's catch-all does not swallow it."""


@dataclass(frozen=True)
class Outcome:
    case: str
    code: int | None
    stderr: str
    handled: bool
    argv: tuple[str, ...] = ()

    def describe(self) -> str:
        return f"{self.case}: exit {self.code}, stderr {self.stderr.strip()[:300]!r}"


def _alarm(signum, frame):
    raise CaseTimeout


def run_case(case: Case, workdir: Path, timeout_s: int = 60) -> Outcome:
    workdir.mkdir(parents=True, exist_ok=True)
    argv = case.build(workdir)
    err, out = io.StringIO(), io.StringIO()
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(timeout_s)
    try:
        with redirect_stderr(err), redirect_stdout(out), warnings.catch_warnings():
            warnings.simplefilter("default")  # as a user's shell would show them
            try:
                code = main(argv)
            except SystemExit as e:
                code = e.code if isinstance(e.code, int) else 2
    except CaseTimeout:
        code = None
        err.write(f"(no answer within {timeout_s} s)\n")
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    text = err.getvalue()
    lines = [ln for ln in text.splitlines() if ln.strip()]
    handled = (code == 2 and len(lines) == 1 and lines[0].startswith("motion2robot: error: ")
               and "internal error" not in lines[0])
    return Outcome(case.name, code, text, handled, tuple(argv))

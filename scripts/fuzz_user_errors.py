"""Run the whole malformed-input corpus (tests/fuzz/corpus.py) through the CLI and print
``N/N handled``: a case is handled when it ends as exactly one ``motion2robot: error: ...`` line on
stderr with exit code 2 (no traceback, no warning lines, no internal error, within 60 s).

    python scripts/fuzz_user_errors.py [--only SUBSTRING] [--verbose]

Exit code 0 when every case is handled, 1 otherwise (the unhandled ones are listed).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.fuzz.corpus import CASES  # noqa: E402
from tests.fuzz.runner import run_case  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", help="run the cases whose name contains this text")
    ap.add_argument("--verbose", action="store_true", help="print every case's error line")
    args = ap.parse_args()
    cases = [c for c in CASES if not args.only or args.only in c.name]
    bad = []
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for k, c in enumerate(cases):
            out = run_case(c, Path(tmp) / f"case{k}")
            if not out.handled:
                bad.append(out)
            if args.verbose or not out.handled:
                mark = "ok  " if out.handled else "FAIL"
                print(f"{mark} {out.describe()}", flush=True)
    print(f"{len(cases) - len(bad)}/{len(cases)} handled ({time.perf_counter() - t0:.0f} s)")
    return 0 if not bad else 1


if __name__ == "__main__":
    sys.exit(main())

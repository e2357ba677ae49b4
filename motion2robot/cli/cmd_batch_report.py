"""``motion2robot batch-report results.jsonl [--csv out.csv] [--html out.html]``: re-summarise a batch."""

from __future__ import annotations

import argparse
import json
import sys

from motion2robot.cli.numbers import number


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "batch-report", help="summarise a (finished or partial) batch results file; export CSV/HTML",
        description="Summarise a results file written by 'motion2robot batch': executable rate, clips failing "
                    "each check, the most common reasons and errors, the slowest clips. A partial file (a "
                    "batch still running or killed) is fine; a torn last line is ignored.")
    p.add_argument("results", help="results file (.jsonl) from 'motion2robot batch'")
    p.add_argument("--csv", metavar="OUT.csv", help="write one line per clip as CSV")
    p.add_argument("--html", metavar="OUT.html", help="write a self-contained HTML report")
    p.add_argument("--json", metavar="OUT.json", help="write the summary as JSON ('-' for stdout)")
    p.add_argument("--top", type=number("lines", 0, 10**6, whole=True), default=10, help="how many reasons / slowest clips to list (default 10)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from motion2robot.batch import format_summary, read_rows, summarize
    from motion2robot.batch.report_html import write_html
    from motion2robot.batch.summary import write_csv
    from motion2robot.errors import InputFileError

    path = Path(args.results)
    if not path.is_file():
        raise InputFileError(f"{path}: no such results file; give the --out file of 'motion2robot batch'")
    result = read_rows(path)
    if not result.rows:
        raise InputFileError(f"{path}: holds no result rows; run 'motion2robot batch ... --out {path}' first")
    if result.bad_lines:
        print(f"batch-report: ignored {len(result.bad_lines)} unreadable line(s) of {path} "
              f"(line {', '.join(map(str, result.bad_lines[:5]))}; a torn write after a crash)", file=sys.stderr)
    rows = list(result.rows)
    summary = summarize(rows, top=args.top)
    robots = sorted({str(r.get("robot")) for r in rows})
    if args.json == "-":
        print(json.dumps(summary.to_dict(), indent=1))
    else:
        print(format_summary(summary, robot=", ".join(robots)))
        if args.json:
            Path(args.json).write_text(json.dumps(summary.to_dict(), indent=1), encoding="utf-8")
    if args.csv:
        print(f"wrote {write_csv(rows, args.csv)}", file=sys.stderr)
    if args.html:
        print(f"wrote {write_html(rows, summary, args.html, title=f'motion2robot batch: {path.name}')}",
              file=sys.stderr)
    return 0

"""``motion2robot batch INPUTS... --robot NAME --out results.jsonl``: feasibility of a whole data set."""

from __future__ import annotations

import argparse
import os
import sys

from motion2robot.cli.numbers import number
from motion2robot.cli.worker_options import add_job_options, add_worker_options, batch_config, check_worker_args


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "batch", help="retarget and check many clips (files, folders, manifests) into a JSONL file",
        description="Read every clip of the INPUTS, retarget it onto the robot and check it; write one JSON "
                    "line per clip to --out as soon as it is done (fsync-ed: a crash loses at most the clips "
                    "in flight). Rerunning skips clips already in the file (resume). Bad files become rows "
                    "with an 'error', never a crashed batch. Ends with a summary (see also 'batch-report').")
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="motion files, folders (searched recursively for .npy .npz .bvh .pt .pth .pkl .amc) "
                        "or manifests (.txt/.lst: one path per line, relative to the manifest)")
    p.add_argument("--out", required=True, help="results file (JSON Lines); appended to and resumed")
    add_worker_options(p)
    p.add_argument("--save-motions", metavar="DIR", help="also save each retargeted robot motion (.npz) here")
    p.add_argument("--redo", action="store_true", help="process every clip again (their old rows are removed)")
    p.add_argument("--redo-errors", action="store_true", help="process again the clips whose row is an error")
    p.add_argument("--max-tasks-per-child", type=number("tasks", 1, 10**9, whole=True), metavar="N",
                   help="restart each local worker after N clips (guards against leaks; default: never)")
    p.add_argument("--pairs", action="store_true",
                   help="INPUTS are edit pairs (editor result files, folders of them, or manifests of SOURCE<TAB>EDIT "
                        "lines): each edit is retargeted keeping what it did not change (see 'edit'); the summary "
                        "gives the share of edits that stay executable")
    add_job_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from motion2robot.batch.results import batch_lock
    from motion2robot.util.output import output_path

    output_path(args.out, "results file", ".jsonl")
    robot, read_options = check_worker_args(args)  # fail fast (exit 2) on an unknown robot
    with batch_lock(args.out):  # before the plan reads or --redo rewrites the results file
        return _run_locked(args, robot, read_options, tqdm)


def _run_locked(args: argparse.Namespace, robot, read_options: dict, tqdm) -> int:  # noqa: ANN001
    from motion2robot.batch import format_summary, plan_batch, read_rows, run_plan, summarize

    expansion = None
    if args.pairs:
        from motion2robot.batch.pairs import expand_pairs

        expansion = expand_pairs(args.inputs)
    plan = plan_batch(args.inputs, args.out, redo=args.redo, redo_errors=args.redo_errors,
                      read_options=read_options, robot=robot.name, expansion=expansion)
    exp = plan.expansion
    files = len({i.path for i in exp.items})
    note = [f"{len(exp.items)} clips in {files} files"]
    copies = [p for p, why in exp.skipped if why.startswith("MoMask copy")]
    other = [p for p, why in exp.skipped if not why.startswith("MoMask copy")]
    if copies:
        note.append(f"{len(copies)} MoMask copies of the same samples skipped (joints/*_ik.npy kept)")
    if other:
        names = ", ".join(os.path.basename(p) for p in other[:4])
        note.append(f"{len(other)} non-motion files skipped ({names})")
    if plan.done:
        note.append(f"{plan.done} already in {args.out} (resume; --redo to redo)")
    if plan.dropped:
        note.append(f"{plan.dropped} old rows removed")
    if plan.bad_lines:
        note.append(f"{len(plan.bad_lines)} unreadable line(s) in {args.out} ignored (torn write after a crash)")
    print("batch: " + "; ".join(note) + f"; {len(plan.todo)} to do", file=sys.stderr)
    config = batch_config(args, robot.name, read_options,
                          job="motion2robot.batch.edit_job:EditJob" if args.pairs else None)
    counts = {"ok": 0, "no": 0, "err": 0}
    with tqdm(total=len(plan.todo), unit="clip", desc="batch", disable=args.quiet, file=sys.stderr,
              dynamic_ncols=True, smoothing=0.05) as bar:
        def on_row(row: dict) -> None:
            counts["err" if row.get("error") else "ok" if row.get("feasible") else "no"] += 1
            bar.set_postfix(executable=counts["ok"], not_exec=counts["no"], errors=counts["err"], refresh=False)
            bar.update()

        run_plan(plan, config, backend=args.backend, jobs=args.jobs, ray_address=args.ray_address,
                 on_row=on_row, max_tasks_per_child=args.max_tasks_per_child)
    keys = plan.keys
    rows = [r for r in read_rows(args.out).rows if r["key"] in keys]
    print(format_summary(summarize(rows), robot=robot.name))
    return 0


"""``motion2robot score INPUTS... --robot NAME --out DIR``: how much of a generator's output a robot
can perform, one table row per INPUT."""

from __future__ import annotations

import argparse
import sys

from motion2robot.cli.worker_options import add_job_options, add_worker_options, batch_config, check_worker_args


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "score", help="score sets of generated samples for a robot: executable share, tempo, fallback, fidelity",
        description="Retarget and check every sample of each INPUT set (as 'batch' does, resumable: each set's rows "
                    "go to OUT/NAME.jsonl, a rerun processes only new samples) and print one table row per set: the "
                    "share of samples executable (every check, physics playback included), the tempo factor they "
                    "needed (median, p90), the share that needed the stance fallback, fidelity (keypoint error of "
                    "the robot vs the scaled human, foot-contact agreement, trajectory error where a path was "
                    "requested), the main failures and the throughput. Also writes OUT/score.csv, .json, .md and "
                    ".html. Every figure but the throughput is deterministic.")
    p.add_argument("inputs", nargs="+", metavar="[NAME=]INPUT",
                   help="one set per INPUT: a folder, motion file or manifest (.txt: one path per line); NAME= labels "
                        "the set (default: the file or folder name)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="folder for the per-set results files (batch JSONL, resumed) and the score files")
    add_worker_options(p)
    p.add_argument("--redo", action="store_true", help="process every sample again (their old rows are removed)")
    add_job_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from motion2robot.score.run import run_score, write_outputs
    from motion2robot.score.table import format_table

    robot, read_options = check_worker_args(args)  # exit 2 on an unknown robot before anything starts
    config = batch_config(args, robot.name, read_options)
    bar = tqdm(total=0, unit="sample", desc="score", disable=args.quiet, file=sys.stderr, dynamic_ncols=True,
               smoothing=0.05)

    def on_plan(sets, todo: int) -> None:  # noqa: ANN001
        done = sum(s.plan.done for s in sets)
        samples = sum(len(s.plan.expansion.items) for s in sets)
        print(f"score: {len(sets)} sets, {samples} samples; {done} already scored in {args.out} (resume; --redo to "
              f"redo); {todo} to do", file=sys.stderr)
        bar.reset(total=todo)

    def on_row(row: dict) -> None:
        bar.update()

    with bar:
        result = run_score(args.inputs, args.out, config, redo=args.redo, read_options=read_options,
                           backend=args.backend, jobs=args.jobs, ray_address=args.ray_address,
                           on_plan=on_plan, on_row=on_row)
    if result.processed:
        print(f"score: processed {result.processed} samples in {result.wall_s:.1f} s wall with {args.jobs} workers "
              f"({60 * result.processed / result.wall_s:.1f} samples/min)", file=sys.stderr)
    paths = write_outputs(result, args.out)  # before printing: a closed stdout (| head) must not lose them
    print(format_table(result.figures, robot.name))
    print("wrote " + ", ".join(str(p) for p in paths), file=sys.stderr)
    return 0

"""Options and set-up shared by the commands that run the batch job over worker processes
(``batch``, ``score``): workers, backend, physics, the retarget/check/read options, the workers'
BatchConfig."""

from __future__ import annotations

import argparse
import os
from typing import Any

from motion2robot.cli.numbers import number


def add_worker_options(p: argparse.ArgumentParser) -> None:
    """--robot, --jobs, --backend, --ray-address, --no-physics, --quiet."""
    p.add_argument("--robot", default="op3", help="robot name (op3, menagerie:unitree_g1, ...) or config path "
                                                  "(default: op3)")
    p.add_argument("--jobs", "-j", type=number("workers", 1, 4096, whole=True), default=os.cpu_count() or 1,
                   help="worker processes / Ray CPUs (default: all cores)")
    p.add_argument("--backend", choices=["local", "ray"], default="local",
                   help="local process pool (default) or Ray tasks (pip install 'motion2robot[ray]')")
    p.add_argument("--ray-address", help="join this Ray cluster (e.g. auto, ray://host:10001) instead of "
                                         "starting a local one")
    p.add_argument("--no-physics", action="store_true",
                   help="kinematic checks only (skip the MuJoCo rollout): much faster")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar")


def add_job_options(p: argparse.ArgumentParser) -> None:
    """The retarget options, the check thresholds and the read options (added last: they are long)."""
    from motion2robot.cli.check_options import add_check_options
    from motion2robot.cli.read_options import add_read_options
    from motion2robot.cli.retarget_options import add_retarget_options

    add_retarget_options(p)
    add_check_options(p)
    add_read_options(p)


def check_worker_args(args: argparse.Namespace) -> tuple[Any, dict[str, Any]]:
    """Validate the worker options (UserError), import Ray when asked; returns the robot (loaded now:
    an unknown robot fails before any worker starts) and the read options given."""
    from motion2robot.cli.read_options import read_args_kwargs
    from motion2robot.errors import UserError
    from motion2robot.robot import load_robot

    if args.jobs < 1:
        raise UserError(f"--jobs {args.jobs}: give at least 1")
    if args.ray_address and args.backend != "ray":
        raise UserError("--ray-address needs --backend ray")
    if args.backend == "ray":
        from motion2robot.batch.ray_backend import import_ray

        import_ray()
    robot = load_robot(args.robot)
    return robot, {k: v for k, v in read_args_kwargs(args).items() if v is not None}


def batch_config(args: argparse.Namespace, robot: str, read_options: dict, job: str | None = None) -> Any:
    """The workers' BatchConfig from the parsed retarget, check and read options."""
    from motion2robot.batch import BatchConfig
    from motion2robot.cli.check_options import check_option_kwargs

    retarget = (("tempo", args.tempo), ("legs", args.legs), ("balance", args.balance))
    if args.tempo_cap is not None:
        retarget += (("tempo_cap", args.tempo_cap),)
    return BatchConfig(robot=robot, physics=not args.no_physics, save_motions=getattr(args, "save_motions", None),
                       read_options=tuple(sorted(read_options.items())), retarget_options=retarget,
                       check_options=tuple(sorted(check_option_kwargs(args).items())), job=job)

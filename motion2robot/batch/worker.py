"""Per-process state of a batch worker and the call that turns one work item into one row.

Each worker process sets its job up ONCE (:func:`initialize`, the pool initializer; Ray workers
call it lazily through :func:`process_with`): for the default
:class:`~motion2robot.batch.feasibility.FeasibilityJob` that loads the robot and compiles its
casadi functions. Then :func:`process` handles clips; every exception becomes an error row with a
one-line message, so one bad clip never stops a batch.
"""

from __future__ import annotations

import importlib
import os
import resource
import sys
import threading
import time
import warnings
from dataclasses import dataclass
from typing import Any

from motion2robot import __version__
from motion2robot.batch.work import WorkItem, one_line
from motion2robot.util import heap


@dataclass(frozen=True)
class BatchConfig:
    """What every worker needs. robot: robot name or config path; physics: run the MuJoCo rollout;
    save_motions: folder for the retargeted motions (None: not saved); read_options: (name, value)
    pairs passed to ``read_motion`` (format, fps, mean, std, units, up, name_map); retarget_options:
    (name, value) pairs of RetargetOptions fields (tempo, legs, tempo_cap, balance); job:
    ``"module:attr"`` of the job object (None: :class:`~motion2robot.batch.feasibility.FeasibilityJob`);
    check_options: (name, value) pairs of CheckOptions fields (thresholds, sag compensation)."""

    robot: str
    physics: bool = True
    save_motions: str | None = None
    read_options: tuple[tuple[str, Any], ...] = ()
    check_options: tuple[tuple[str, Any], ...] = ()
    job: str | None = None
    retarget_options: tuple[tuple[str, Any], ...] = ()


#: At most this many distinct warnings are kept per row.
MAX_WARNINGS = 5


class _State:
    config: BatchConfig | None = None
    job: Any = None
    state: Any = None
    error: str | None = None


_STATE = _State()


def load_job(spec: str | None) -> Any:
    """The job object named by ``"module:attr"`` (None: the feasibility job)."""
    if spec is None:
        from motion2robot.batch.feasibility import FeasibilityJob

        return FeasibilityJob
    module, _, attr = spec.partition(":")
    return getattr(importlib.import_module(module), attr)


def _watch_parent(parent: int) -> None:
    """Exit this worker when the driver dies (SIGKILL leaves the driver no time to stop the pool)."""
    while True:
        time.sleep(0.5)
        if os.getppid() != parent:
            os._exit(0)


def _in_pool_child() -> bool:
    import multiprocessing

    return multiprocessing.parent_process() is not None


def initialize(config: BatchConfig, watch_parent: bool = True) -> None:
    """Set the job up in this process, once per config (load the robot, compile its functions).

    Never raises: a failure (unknown robot, broken model) is kept and reported as the error of
    every row, so a batch ends with error rows rather than a pool that keeps dying.
    """
    if _STATE.config == config:
        return
    if watch_parent and _in_pool_child():
        threading.Thread(target=_watch_parent, args=(os.getppid(),), daemon=True).start()
    _STATE.config, _STATE.error, _STATE.state = config, None, None
    try:
        with warnings.catch_warnings():  # library notices at import/compile time: not about a clip
            warnings.simplefilter("ignore")
            _STATE.job = load_job(config.job)
            _STATE.state = _STATE.job.setup(config)
    except Exception as err:  # noqa: BLE001
        _STATE.error = f"setup: {one_line(err)}"


def base_row(item: WorkItem, config: BatchConfig) -> dict[str, Any]:
    """A row with every schema key (see :mod:`motion2robot.batch`), nothing known yet."""
    return {
        "key": item.key, "path": item.path, "clip": item.clip,
        "frames": None, "fps": None, "duration_s": None, "prompt": None,
        "feasible": None, "failed_checks": [], "reasons": [], "figures": {},
        "timings": {"read_s": None, "retarget_s": None, "check_s": None, "total_s": None, "cpu_s": None},
        "error": None, "robot": config.robot, "version": __version__, "motion_file": None,
        "worker": None, "warnings": [], "fidelity": None,
    }


def worker_figures() -> dict[str, Any]:
    """This process's id and peak resident memory so far (MB)."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    scale = 1 / 1024 / 1024 if sys.platform == "darwin" else 1 / 1024  # bytes on macOS, KiB on Linux
    return {"pid": os.getpid(), "max_rss_mb": round(peak * scale, 1)}


def process(item: WorkItem) -> dict[str, Any]:
    """One row for one clip; never raises (an exception becomes ``"<stage>: <message>"`` in the
    row's ``error``). Needs :func:`initialize` to have run in this process."""
    return _process(item, lambda state, row, stage, config: _STATE.job.run(item, state, row, stage, config))


def process_clip(item: WorkItem, human: Any) -> tuple[dict[str, Any], Any]:
    """(row, robot motion or None) of a clip already in memory (the in-process API): the job's
    ``evaluate`` instead of read + ``run``; never raises, like :func:`process`."""
    out: dict[str, Any] = {}

    def body(state: Any, row: dict[str, Any], stage: list[str], config: BatchConfig) -> None:
        out["motion"] = _STATE.job.evaluate(human, state, row, stage)

    return _process(item, body), out.get("motion")


def _process(item: WorkItem, body: Any) -> dict[str, Any]:
    config = _STATE.config
    if config is None:
        raise RuntimeError("initialize() has not run in this process")
    row = base_row(item, config)
    start, cpu = time.perf_counter(), time.process_time()
    stage = ["setup"]
    if _STATE.error:
        row["error"] = _STATE.error
    else:
        with warnings.catch_warnings(record=True) as caught:  # into the row, not over the progress bar
            warnings.simplefilter("always")
            try:
                body(_STATE.state, row, stage, config)
            except Exception as err:  # noqa: BLE001 - the row carries the problem, the batch goes on
                row["error"] = f"{stage[0]}: {one_line(err)}"
        row["warnings"] = list(dict.fromkeys(
            f"{w.category.__name__}: {' '.join(str(w.message).split())[:300]}" for w in caught))[:MAX_WARNINGS]
    row["timings"]["total_s"] = round(time.perf_counter() - start, 4)
    row["timings"]["cpu_s"] = round(time.process_time() - cpu, 4)
    heap.after_clip()  # what the clip freed back to the OS (not timed: it is the worker's, not the clip's)
    row["worker"] = worker_figures()
    return row


def process_with(config: BatchConfig, item: WorkItem) -> dict[str, Any]:
    """:func:`process` in a process that may not be set up yet (Ray tasks): sets the job up once
    per process and config, then processes the clip."""
    initialize(config, watch_parent=False)
    return process(item)

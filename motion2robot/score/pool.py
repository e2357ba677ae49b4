"""Worker processes kept alive between calls of the in-process API.

One pool per :class:`~motion2robot.batch.worker.BatchConfig`: its workers load the robot and its
compiled problems once (:func:`~motion2robot.batch.worker.initialize`) and then serve every later
call with the same robot and options, so a generation loop pays the start-up once. Clips travel to
the workers in memory (no files). A call with another config replaces the pool; :func:`close`
(also run at exit) stops it. A worker that dies (a crash in a native library) breaks the pool: the
unfinished clips are retried one at a time in a fresh pool, and one that kills its worker alone
gets an error row.
"""

from __future__ import annotations

import atexit
import multiprocessing
import os
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Callable, Sequence

from motion2robot.batch.local import THREAD_VARS, crash_row
from motion2robot.batch.work import WorkItem
from motion2robot.batch.worker import BatchConfig, initialize, process_clip

Result = tuple[dict[str, Any], Any]


class _Pool:
    executor: ProcessPoolExecutor | None = None
    config: BatchConfig | None = None
    jobs: int = 0


_POOL = _Pool()


def close() -> None:
    """Stop the worker processes of the in-process API (they start again on the next call)."""
    if _POOL.executor is not None:
        _POOL.executor.shutdown(wait=True, cancel_futures=True)
    _POOL.executor, _POOL.config, _POOL.jobs = None, None, 0


atexit.register(close)


def _executor(config: BatchConfig, jobs: int) -> ProcessPoolExecutor:
    if _POOL.executor is None or _POOL.config != config or _POOL.jobs != jobs:
        close()
        for var in THREAD_VARS:  # one thread per worker: `jobs` workers use `jobs` cores
            os.environ.setdefault(var, "1")
        _POOL.executor = ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn"),
                                             initializer=initialize, initargs=(config,))
        _POOL.config, _POOL.jobs = config, jobs
    return _POOL.executor


def run_clips(items: Sequence[WorkItem], clips: Sequence[Any], config: BatchConfig, jobs: int,
              on_result: Callable[[int, Result], None] | None = None) -> list[Result]:
    """(row, robot motion) of every clip, in order. ``jobs`` 0: in this process, no workers."""
    results: list[Result | None] = [None] * len(items)

    def done(i: int, res: Result) -> None:
        results[i] = res
        if on_result:
            on_result(i, res)

    if jobs == 0:
        initialize(config, watch_parent=False)
        for i, (item, clip) in enumerate(zip(items, clips)):
            done(i, process_clip(item, clip))
        return results  # type: ignore[return-value]
    todo = list(range(len(items)))
    alone = False
    while todo:
        ex = _executor(config, jobs)
        batch = todo[:1] if alone else todo
        futures: dict[int, Future] = {i: ex.submit(process_clip, items[i], clips[i]) for i in batch}
        failed = []
        for i, fut in futures.items():
            try:
                done(i, fut.result())
            except BrokenProcessPool:
                failed.append(i)
        if failed:
            close()
            if alone:  # it died on its own: this clip is the culprit
                done(failed[0], (crash_row(items[failed[0]], config), None))
                failed = failed[1:]
            alone = True
        todo = failed + [i for i in todo if i not in futures]
    return results  # type: ignore[return-value]

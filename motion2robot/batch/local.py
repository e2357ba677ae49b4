"""Local backend: a pool of worker processes on this machine, results streamed back as they finish.

- ``spawn`` start method: workers import the package afresh (no forked threads or MuJoCo state),
  then :func:`~motion2robot.batch.worker.initialize` loads the robot and compiles its casadi
  functions once per worker.
- Bounded submission: at most ``max_in_flight`` clips are queued at any time, so the driver's
  memory does not grow with the number of clips; rows are yielded in completion order.
- A worker that dies (segfault, out of memory) breaks the pool: the clips that were in flight are
  retried one at a time in a fresh pool; a clip whose worker dies while it runs alone gets an
  error row, the others their normal rows.
- ``max_tasks_per_child`` restarts workers after that many clips (recompiling once each), a
  guard against slow leaks in native libraries; None keeps them for the whole batch.
"""

from __future__ import annotations

import multiprocessing
import os
from collections import deque
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Iterable, Iterator

from motion2robot.batch.worker import BatchConfig, base_row, initialize, process
from motion2robot.batch.work import WorkItem

#: Thread pools of numerical libraries, one thread each in workers unless the user set them:
#: ``jobs`` single-threaded workers then use ``jobs`` cores without oversubscription.
THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def run_local(items: Iterable[WorkItem], config: BatchConfig, jobs: int = 2, *,
              max_in_flight: int | None = None, max_tasks_per_child: int | None = None) -> Iterator[dict]:
    """Process ``items`` with ``jobs`` worker processes; yields one row per item as it finishes."""
    if jobs < 1:
        raise ValueError(f"jobs must be >= 1, got {jobs}")
    limit = max_in_flight or 4 * jobs
    pending: deque[WorkItem] = deque(items)
    suspects: deque[WorkItem] = deque()  # in flight when a worker died: retried one at a time
    ctx = multiprocessing.get_context("spawn")
    for var in THREAD_VARS:  # inherited by the spawned workers
        os.environ.setdefault(var, "1")
    while pending or suspects:
        executor = ProcessPoolExecutor(jobs, mp_context=ctx, initializer=initialize, initargs=(config,),
                                       max_tasks_per_child=max_tasks_per_child)
        in_flight: dict[Future, tuple[WorkItem, bool]] = {}
        broken = False
        try:
            while True:
                while not broken and (suspects or pending):
                    if suspects:  # alone in the pool, so a death names the culprit
                        if in_flight:
                            break
                        item, alone = suspects.popleft(), True
                    elif len(in_flight) < limit:
                        item, alone = pending.popleft(), False
                    else:
                        break
                    try:
                        in_flight[executor.submit(process, item)] = (item, alone)
                    except BrokenProcessPool:
                        (suspects if alone else pending).appendleft(item)
                        broken = True
                    if alone:
                        break
                if not in_flight:
                    break
                done, _ = wait(in_flight, return_when=FIRST_COMPLETED)
                for fut in done:
                    item, alone = in_flight.pop(fut)
                    try:
                        yield fut.result()
                    except BrokenProcessPool:
                        broken = True
                        if alone:
                            yield crash_row(item, config)
                        else:
                            suspects.append(item)
                    except Exception as err:  # noqa: BLE001 - e.g. a row that failed to pickle
                        row = base_row(item, config)
                        row["error"] = f"worker: {type(err).__name__}: {' '.join(str(err).split())}"
                        yield row
                if broken and not in_flight:
                    break
        finally:
            executor.shutdown(wait=not broken, cancel_futures=True)


def crash_row(item: WorkItem, config: BatchConfig) -> dict:
    row = base_row(item, config)
    row["error"] = ("worker: the worker process died while processing this clip alone (a crash or out of "
                    "memory in a native library); try it with 'motion2robot check' to see more")
    return row

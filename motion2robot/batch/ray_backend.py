"""Ray backend: the same work items as Ray tasks, rows streamed back to the driver as they finish.

Ray is an optional extra (``pip install 'motion2robot[ray]'``) and is imported only here. With
``address=None`` a local Ray instance is started with ``jobs`` CPUs (and shut down afterwards);
with an address (``auto``, ``ray://host:10001``) the batch joins that cluster, whose workers must
have motion2robot installed. Each Ray worker process loads the robot and compiles its functions
once (:func:`~motion2robot.batch.worker.process_with` caches them per process), then reuses them
for every task it runs. At most ``max_in_flight`` tasks are submitted at a time.
"""

from __future__ import annotations

from typing import Any, Iterable, Iterator

from motion2robot.batch.work import WorkItem
from motion2robot.batch.worker import BatchConfig, base_row, process_with
from motion2robot.errors import UserError


def import_ray() -> Any:
    try:
        import ray
    except ImportError as err:
        raise UserError("--backend ray needs the Ray package, which is not installed; "
                        "run: pip install 'motion2robot[ray]' (or use --backend local)") from err
    return ray


def run_ray(items: Iterable[WorkItem], config: BatchConfig, jobs: int = 2, *, address: str | None = None,
            max_in_flight: int | None = None) -> Iterator[dict]:
    """Process ``items`` as Ray tasks; yields one row per item in completion order."""
    ray = import_ray()
    started = False
    if not ray.is_initialized():
        kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                                  "ignore_reinit_error": True}
        if address:
            kwargs["address"] = address
        else:
            kwargs["num_cpus"] = jobs
        try:
            ray.init(**kwargs)
        except Exception as err:  # noqa: BLE001 - connection refused, bad address, ...
            where = f"the Ray cluster at {address}" if address else "a local Ray instance"
            raise UserError(f"cannot start or reach {where} ({' '.join(str(err).split())}); "
                            "check --ray-address, or use --backend local") from err
        started = True
    task = ray.remote(num_cpus=1, max_retries=1)(process_with)
    limit = max_in_flight or 4 * max(1, int(ray.cluster_resources().get("CPU", jobs)))
    config_ref = ray.put(config)
    pending = iter(items)
    in_flight: dict[Any, WorkItem] = {}
    try:
        while True:
            for item in pending:
                in_flight[task.remote(config_ref, item)] = item
                if len(in_flight) >= limit:
                    break
            if not in_flight:
                break
            done, _ = ray.wait(list(in_flight), num_returns=1)
            for ref in done:
                item = in_flight.pop(ref)
                try:
                    yield ray.get(ref)
                except Exception as err:  # noqa: BLE001 - worker crash, task cancelled, ...
                    row = base_row(item, config)
                    row["error"] = f"ray: {type(err).__name__}: {' '.join(str(err).split())[:300]}"
                    yield row
    finally:
        for ref in in_flight:
            ray.cancel(ref, force=True)
        if started:
            ray.shutdown()

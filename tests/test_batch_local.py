"""The local process-pool backend, with a probe job (fast, and able to crash its worker on demand).

The probe job runs in spawned worker processes, which import it from this module by name.
"""

from __future__ import annotations

import os
import time
import warnings

import numpy as np

from motion2robot.batch.local import run_local
from motion2robot.batch.work import WorkItem
from motion2robot.batch.worker import BatchConfig

_SETUPS = 0


class ProbeJob:
    """``setup`` counts its calls per process; ``run`` reads the clip's frame count and acts on
    the file name: ``crash*`` kills the worker (like a segfault), ``boom*`` raises."""

    @staticmethod
    def setup(config):
        global _SETUPS
        _SETUPS += 1
        return {"setups": _SETUPS}

    @staticmethod
    def run(item, state, row, stage, config):
        stage[0] = "read"
        name = os.path.basename(item.path)
        frames = int(np.load(item.path, mmap_mode="r").shape[0])
        row.update(frames=frames, feasible=frames % 2 == 0, figures={"setups": state["setups"]})
        if name == "c03.npy":
            warnings.warn("probe\nwarning", stacklevel=1)
            warnings.warn("probe\nwarning", stacklevel=1)
        if name.startswith("crash"):
            os._exit(13)
        if name.startswith("boom"):
            stage[0] = "check"
            raise ValueError(f"probe failure on\n{name}")
        time.sleep(0.01)


class BrokenSetupJob:
    @staticmethod
    def setup(config):
        raise RuntimeError("no such robot model")

    @staticmethod
    def run(item, state, row, stage, config):  # pragma: no cover - never reached
        raise AssertionError


def _items(tmp_path, names: list[str]) -> list[WorkItem]:
    out = []
    for k, name in enumerate(names):
        p = tmp_path / f"{name}.npy"
        np.save(p, np.zeros((10 + k, 22, 3), np.float32))
        out.append(WorkItem(str(p), 0))
    return out


def test_rows_stream_back_once_each_and_setup_runs_once_per_worker(tmp_path):
    items = _items(tmp_path, [f"c{i:02d}" for i in range(10)] + ["boom_a"])
    config = BatchConfig(robot="probe", job="tests.test_batch_local:ProbeJob")
    rows = list(run_local(items, config, jobs=2, max_in_flight=3))
    assert sorted(r["key"] for r in rows) == sorted(i.key for i in items)
    good = [r for r in rows if not r["error"]]
    assert len(good) == 10
    assert all(r["frames"] == 10 + int(os.path.basename(r["path"])[1:3]) for r in good)
    assert {r["figures"]["setups"] for r in good} == {1}  # one setup per worker process
    assert len({r["worker"]["pid"] for r in rows}) <= 2 and all(r["worker"]["max_rss_mb"] > 0 for r in rows)
    assert [r["warnings"] for r in rows if r["path"].endswith("c03.npy")] == [["UserWarning: probe warning"]]
    assert sum(bool(r["warnings"]) for r in rows) == 1
    (bad,) = [r for r in rows if r["error"]]
    assert bad["error"] == "check: ValueError: probe failure on boom_a.npy"  # one line, with the stage
    assert bad["frames"] == 20 and bad["timings"]["total_s"] >= 0


def test_a_dying_worker_costs_only_its_clip(tmp_path):
    items = _items(tmp_path, ["a", "crash_me", "b", "c"])
    config = BatchConfig(robot="probe", job="tests.test_batch_local:ProbeJob")
    rows = {r["key"]: r for r in run_local(items, config, jobs=1, max_in_flight=2)}
    assert set(rows) == {i.key for i in items}
    crashed = rows[items[1].key]
    assert "died while processing this clip alone" in crashed["error"]
    assert all(rows[i.key]["error"] is None for i in items if i is not items[1])


def test_setup_failure_becomes_every_rows_error(tmp_path):
    items = _items(tmp_path, ["a", "b"])
    config = BatchConfig(robot="probe", job="tests.test_batch_local:BrokenSetupJob")
    rows = list(run_local(items, config, jobs=1))
    assert [r["error"] for r in rows] == ["setup: RuntimeError: no such robot model"] * 2


def test_workers_are_recycled_after_max_tasks_per_child(tmp_path):
    items = _items(tmp_path, ["a", "b", "c", "d", "e"])
    config = BatchConfig(robot="probe", job="tests.test_batch_local:ProbeJob")
    rows = list(run_local(items, config, jobs=1, max_in_flight=1, max_tasks_per_child=2))
    assert len(rows) == 5 and all(r["error"] is None for r in rows)
    assert len({r["worker"]["pid"] for r in rows}) == 3  # a fresh worker (set up once) every 2 clips
    assert {r["figures"]["setups"] for r in rows} == {1}

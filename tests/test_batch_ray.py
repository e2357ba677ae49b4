"""The Ray backend against a local Ray instance (skipped when Ray is not installed)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from motion2robot.batch.run import plan_batch, run_plan
from motion2robot.batch.worker import BatchConfig
from tests.test_batch_local import _items

REPO = Path(__file__).resolve().parents[1]


def test_missing_ray_is_a_user_error(monkeypatch):
    from motion2robot.batch.ray_backend import import_ray
    from motion2robot.errors import UserError

    monkeypatch.setitem(sys.modules, "ray", None)  # import ray -> ImportError
    with pytest.raises(UserError, match=r"pip install 'motion2robot\[ray\]'"):
        import_ray()


def test_ray_tasks_stream_rows_into_the_same_jsonl(tmp_path, monkeypatch):
    pytest.importorskip("ray")
    # Ray's worker processes inherit the environment of ray.init: let them import the probe job.
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    monkeypatch.setenv("RAY_USAGE_STATS_ENABLED", "0")
    items = _items(tmp_path, ["a", "b", "boom_c", "d"])
    out = tmp_path / "r.jsonl"
    plan = plan_batch([tmp_path], out)
    assert len(plan.todo) == 4
    seen = []
    config = BatchConfig(robot="probe", job="tests.test_batch_local:ProbeJob")
    n = run_plan(plan, config, backend="ray", jobs=1, on_row=seen.append)
    assert n == 4 and sorted(r["key"] for r in seen) == sorted(i.key for i in items)
    lines = out.read_text().splitlines()
    assert len(lines) == 4
    by_name = {os.path.basename(r["path"]): r for r in seen}
    assert by_name["boom_c.npy"]["error"] == "check: ValueError: probe failure on boom_c.npy"
    assert by_name["a.npy"]["frames"] == 10 and by_name["a.npy"]["error"] is None
    assert {r["figures"].get("setups") for r in seen if not r["error"]} == {1}  # set up once per Ray worker
    assert plan_batch([tmp_path], out).todo == ()  # resumable like the local backend

"""The append-only JSONL results file: fsync-ed rows, torn last lines, resume and redo."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motion2robot.batch.results import ResultWriter, dumps_row, read_rows, rewrite_without
from motion2robot.batch.run import plan_batch
from motion2robot.errors import UserError


def _row(key: str, **extra) -> dict:
    return {"key": key, "error": None, "robot": "op3", **extra}


def test_rows_round_trip_with_numpy_and_nan(tmp_path):
    out = tmp_path / "r.jsonl"
    with ResultWriter(out) as w:
        w.write(_row("a#0", figures={"max": np.float32(1.5), "arr": np.arange(3), "bad": float("nan")}))
        w.write(_row("b#0", figures={"inf": np.inf}))
    lines = out.read_text().splitlines()
    assert len(lines) == 2 and all(json.loads(x) for x in lines)
    res = read_rows(out)
    assert [r["key"] for r in res.rows] == ["a#0", "b#0"]
    assert res.rows[0]["figures"] == {"max": 1.5, "arr": [0, 1, 2], "bad": None}
    assert res.rows[1]["figures"] == {"inf": None}
    assert res.bad_lines == ()


def test_torn_last_line_is_ignored_then_cut_before_appending(tmp_path):
    out = tmp_path / "r.jsonl"
    good = dumps_row(_row("a#0"))
    torn = dumps_row(_row("b#0", reasons=["x" * 50]))[:30]
    out.write_text(good + "\n" + torn)
    res = read_rows(out)
    assert res.keys == {"a#0"} and res.bad_lines == (2,)
    with ResultWriter(out) as w:
        assert w.torn_bytes == len(torn)
        w.write(_row("b#0"))
    assert [json.loads(x)["key"] for x in out.read_text().splitlines()] == ["a#0", "b#0"]


def test_file_of_only_a_torn_line(tmp_path):
    out = tmp_path / "r.jsonl"
    out.write_text('{"key": "a')
    with ResultWriter(out) as w:
        w.write(_row("a#0"))
    assert read_rows(out).keys == {"a#0"}
    assert out.read_text().count("\n") == 1


def test_a_second_writer_on_the_same_file_is_refused(tmp_path):
    out = tmp_path / "r.jsonl"
    with ResultWriter(out) as w:
        w.write(_row("a#0"))
        with pytest.raises(UserError, match="another batch is writing"):
            ResultWriter(out)
    with ResultWriter(out) as w:  # free again once the first one closed
        w.write(_row("b#0"))
    assert read_rows(out).keys == {"a#0", "b#0"}


def test_duplicate_keys_keep_the_last_row(tmp_path):
    out = tmp_path / "r.jsonl"
    with ResultWriter(out) as w:
        w.write(_row("a#0", feasible=False))
        w.write(_row("b#0"))
        w.write(_row("a#0", feasible=True))
    res = read_rows(out)
    assert [r["key"] for r in res.rows] == ["b#0", "a#0"] and res.rows[1]["feasible"] is True


def test_rewrite_without_drops_only_those_keys(tmp_path):
    out = tmp_path / "r.jsonl"
    with ResultWriter(out) as w:
        w.write_all([_row("a#0"), _row("b#0"), _row("c#0")])
    with open(out, "a") as fh:
        fh.write("{torn")
    assert rewrite_without(out, {"b#0", "zzz"}) == 1
    assert [r["key"] for r in read_rows(out).rows] == ["a#0", "c#0"]
    assert read_rows(out).bad_lines == ()


def test_plan_resumes_and_redoes(tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    for name in "abc":
        np.save(data / f"{name}.npy", np.zeros((10, 22, 3), np.float32))
    out = tmp_path / "r.jsonl"
    keys = [f"{(data / n).resolve()}.npy#0" for n in "abc"]
    with ResultWriter(out) as w:
        w.write(_row(keys[0]))
        w.write(_row(keys[1], error="read: broken"))
        w.write(_row("/elsewhere/other.npy#0"))
    plan = plan_batch([data], out)
    assert plan.done == 2 and [i.key for i in plan.todo] == [keys[2]]
    with pytest.raises(UserError, match="for robot op3, not menagerie:unitree_g1"):
        plan_batch([data], out, robot="menagerie:unitree_g1")
    plan = plan_batch([data], out, redo_errors=True)
    assert plan.dropped == 1 and [i.key for i in plan.todo] == keys[1:]
    plan = plan_batch([data], out, redo=True)
    assert plan.done == 0 and len(plan.todo) == 3
    assert read_rows(out).keys == {"/elsewhere/other.npy#0"}  # rows of other inputs survive --redo

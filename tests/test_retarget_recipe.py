"""A process finds the robot's compiled lane library by the recipe digest without building the
casadi graph, and gets the same numbers; any change to what the code is made from changes the
digest; a damaged record is ignored."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from motion2robot.retarget import compiled as C
from motion2robot.retarget.compiled import _recipe_lookup, _recipe_path, compiled_problem
from motion2robot.retarget.costs import FRAME_TERMS
from motion2robot.retarget.recipe import recipe_digest
from motion2robot.retarget.targets import frame_params
from motion2robot.robot import load_robot


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def test_recorded_library_loads_without_the_graph_and_matches_the_vm(op3, monkeypatch):
    if C._compiler() is None:
        pytest.skip("no C compiler")
    compiled_problem.cache_clear()
    first = compiled_problem(op3)                     # builds (or finds) the library, records it
    if first.backend != "lanes":
        pytest.skip("no lane code on this machine")
    assert _recipe_path(first.spec).is_file()
    compiled_problem.cache_clear()

    def no_graph(spec):
        raise AssertionError("the casadi graph was built although the recipe was recorded")

    monkeypatch.setattr(C, "build_functions", no_graph)
    again = compiled_problem(op3)
    assert again.backend == "lanes" and again.cached and again.functions == {}
    monkeypatch.undo()
    vm = compiled_problem(op3, "vm")
    rng = np.random.default_rng(0)
    T = 5
    Q = np.tile(op3.nominal_qpos, (T, 1))
    Q[:, 7:] += rng.uniform(-0.3, 0.3, (T, op3.n_joints))
    labels = rng.uniform(size=(T, 2)) < 0.5
    P = frame_params(again.spec, rng.normal(size=(T, 22, 3)) * 0.2, labels, None, None, None)
    w = np.ones(len(FRAME_TERMS))
    for name, args in (("points", (Q,)), ("violation", (Q, P)), ("cost", (Q, P, w))):
        for a, b in zip(again.evaluator(name, T)(*args), vm.evaluator(name, T)(*args)):
            assert np.all(np.isfinite(a)) and np.allclose(a, b, rtol=1e-12, atol=1e-12)
    compiled_problem.cache_clear()


def test_digest_follows_the_spec_and_the_build(op3):
    spec = compiled_problem(op3).spec
    base = recipe_digest(spec, "flags")
    assert recipe_digest(spec, "flags") == base
    assert recipe_digest(spec, "other flags") != base
    pair = spec.capsules[0]
    moved = dataclasses.replace(spec, capsules=(dataclasses.replace(pair, allowance=pair.allowance + 1e-9),
                                                *spec.capsules[1:]))
    assert recipe_digest(moved, "flags") != base
    assert recipe_digest(dataclasses.replace(spec, length=spec.length * (1 + 1e-12)), "flags") != base


def test_damaged_records_are_ignored(tmp_path):
    bad = tmp_path / "recipe-x.json"
    for text in ("not json", '{"library": "gone.so", "signatures": {}}', '{"library": 3}'):
        bad.write_text(text)
        assert _recipe_lookup(bad) is None
    assert _recipe_lookup(tmp_path / "missing.json") is None


def _package_imports(path) -> set[str]:
    """Modules of the package ``path`` imports (top level or inside functions), as paths below it."""
    import ast

    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        names = []
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("motion2robot."):
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names if a.name.startswith("motion2robot.")]
        for name in names:
            rel = name.split(".", 1)[1].replace(".", "/")
            out.add(rel + ".py")
    return out


def test_the_hashed_sources_are_closed_under_their_imports():
    """Every module of ``retarget`` or ``robot`` that a hashed module imports is hashed too
    (package __init__ files aside, which only re-export), so no code the graph is made by escapes
    the digest. (Modules elsewhere only make data the spec carries, which is hashed field by field.)"""
    from motion2robot.retarget.recipe import _PACKAGE, graph_sources

    hashed = {p.relative_to(_PACKAGE).as_posix() for p in graph_sources()}
    for path in graph_sources():
        for rel in _package_imports(path):
            if rel.startswith(("retarget/", "robot/")) and (_PACKAGE / rel).is_file() \
                    and not rel.endswith("__init__.py"):
                assert rel in hashed, f"{path.name} imports {rel}, which the recipe digest does not hash"

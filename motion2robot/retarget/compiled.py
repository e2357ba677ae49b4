"""Compile the problem's casadi functions to C once per robot and cache the shared library.

Three backends, best first:

- ``"lanes"``: C from :mod:`~motion2robot.retarget.lanes` (several frames per vector operation),
  one file per function compiled in parallel;
- ``"c"``: casadi's own code generator (one frame at a time), if lane code cannot be made;
- ``"vm"``: casadi's virtual machine when there is no C compiler (slower, same numbers).

The generated C source is hashed; the library lives in ``$MOTION2ROBOT_CACHE`` (default
``~/.cache/motion2robot``) as ``lanes/<hash>.so`` or ``casadi/<hash>.so``, so a second process
(or a second run) only loads it. The hash covers the compiler flags, which name the vector
instruction set, so a cache shared by different machines never hands one a library it cannot run.
A lane library is also recorded under the digest of what its code is made from
(:mod:`~motion2robot.retarget.recipe`, ``lanes/recipe-<digest>.json``: the library's file and the
functions' signatures), so later processes load it without building the casadi graph at all.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import json
import os
import shutil
import subprocess
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from motion2robot.retarget import lanes
from motion2robot.retarget.problem import ProblemSpec, build_functions, build_spec
from motion2robot.retarget.recipe import recipe_digest
from motion2robot.robot.robot import Robot
from motion2robot.util.cache import cache_dir, write_atomic

CFLAGS = ("-O1", "-fPIC", "-shared")  # casadi's code: -O2 runs ~10 % faster but compiles ~2x longer
#: Lane code: -O1; no FMA contraction, so the numbers are casadi's.
LANE_CFLAGS = ("-O1", "-fPIC", "-ffp-contract=off")
#: Inputs shared by all frames (the term weights ``w``), per function.
SHARED_INPUTS = {"step": (2,), "cost": (2,)}
BACKENDS = ("auto", "lanes", "c", "vm")
#: The functions of :func:`~motion2robot.retarget.problem.build_functions`.
FUNCTIONS = ("step", "cost", "project", "settle", "violation", "points")


def _compiler() -> str | None:
    return shutil.which(os.environ.get("CC", "gcc"))


@dataclass(frozen=True, eq=False)
class CompiledProblem:
    """A robot's problem ready to evaluate: the ``step``/``cost``/``project``/``settle``/``violation``/``points``
    casadi functions of :func:`~motion2robot.retarget.problem.build_functions` (compiled per
    ``backend``), the spec, and how long building/compiling took (s)."""

    spec: ProblemSpec
    functions: dict[str, ca.Function]   # empty when the lane library was found by its recipe
    backend: str
    build_s: float
    compile_s: float
    cached: bool
    library: ctypes.CDLL | None = None  # the lane code, backend "lanes"
    signatures: dict | None = None      # name -> (C name, input sizes, output sizes), lane code

    @functools.lru_cache(maxsize=16)
    def _lane(self, name: str) -> lanes.LaneEval:
        f = self.functions.get(name) or tuple(self.signatures[name])
        return lanes.LaneEval(self.library, f, SHARED_INPUTS.get(name, ()))

    @functools.lru_cache(maxsize=40)
    def _mapped(self, name: str, frames: int) -> MappedEval:
        f = self.functions[name]
        shared = SHARED_INPUTS.get(name, ())
        if shared:
            return MappedEval(f.map(f"{f.name()}_map", "serial", frames, list(shared), []), frames)
        return MappedEval(f.map(frames, "serial"), frames)

    def evaluator(self, name: str, frames: int):
        """Callable evaluating function ``name`` on ``frames`` frames: inputs (frames, size) arrays
        (the weights ``w`` one vector), outputs (frames, size) arrays."""
        return self._lane(name) if self.library is not None else self._mapped(name, frames)

    def step_eval(self, frames: int):
        return self.evaluator("step", frames)

    def cost_eval(self, frames: int):
        return self.evaluator("cost", frames)

    def project_eval(self, frames: int):
        return self.evaluator("project", frames)

    def settle_eval(self, frames: int):
        return self.evaluator("settle", frames)

    def violation_eval(self, frames: int):
        return self.evaluator("violation", frames)

    def points_eval(self, frames: int):
        return self.evaluator("points", frames)


class MappedEval:
    """Calls a frame-mapped casadi function on numpy arrays without conversions: inputs and
    outputs live in preallocated C-contiguous arrays of shape (frames, size) (= casadi's
    column-major (size, frames)), bound once through casadi's buffer interface."""

    def __init__(self, fmap: ca.Function, frames: int):
        self._f = fmap
        self._buf, self._eval = fmap.buffer()
        self.args = [np.zeros((fmap.size1_in(i), fmap.size2_in(i))[::-1]) for i in range(fmap.n_in())]
        self.res = [np.zeros((fmap.size1_out(i), fmap.size2_out(i))[::-1]) for i in range(fmap.n_out())]
        for i, a in enumerate(self.args):
            self._buf.set_arg(i, memoryview(a))
        for i, r in enumerate(self.res):
            self._buf.set_res(i, memoryview(r))
        self.frames = frames

    def __call__(self, *inputs: np.ndarray) -> list[np.ndarray]:
        """Evaluate; each input is copied into its bound array; returns copies of the outputs,
        each reshaped to (frames, size)."""
        for a, x in zip(self.args, inputs):
            a[...] = np.reshape(x, a.shape)
        self._eval()
        return [r.reshape(self.frames, -1).copy() for r in self.res]


def _run(cmd: list[str]) -> None:
    subprocess.run(cmd, check=True, capture_output=True)


def _compile(src: Path, out: Path, extra: tuple[str, ...] = ()) -> None:
    """``src`` compiled with CFLAGS (and ``extra``: flags, libraries) into the library ``out``."""
    cc = os.environ.get("CC", "gcc")
    tmp = out.with_name(out.name + f".{os.getpid()}.tmp")
    _run([cc, *CFLAGS, str(src), *extra, "-o", str(tmp), "-lm"])
    tmp.replace(out)  # atomic: concurrent processes never load a half-written library


def cached_library(name: str, source: str, extra: tuple[str, ...] = (), salt: str = "") -> ctypes.CDLL | None:
    """The C ``source`` compiled (CFLAGS + ``extra``) into ``$MOTION2ROBOT_CACHE/native/<name>-<digest>.so``
    on first use and loaded; the digest covers the source, the flags and ``salt`` (e.g. a library
    version the code is built against). None without a C compiler, with ``MOTION2ROBOT_NATIVE=0``,
    or when the build or the cache fails (the callers run their Python versions)."""
    if os.environ.get("MOTION2ROBOT_NATIVE", "1") == "0" or _compiler() is None:
        return None
    digest = hashlib.sha256((source + " ".join(CFLAGS + extra) + salt).encode()).hexdigest()[:20]
    lib = cache_dir() / "native" / f"{name}-{digest}.so"
    try:
        if not lib.is_file():
            lib.parent.mkdir(parents=True, exist_ok=True)
            src = lib.with_name(f"{name}-{digest}.{os.getpid()}.c")
            src.write_text(source)
            try:
                _compile(src, lib, extra)
            finally:
                src.unlink(missing_ok=True)
        return ctypes.CDLL(str(lib))
    except (OSError, subprocess.CalledProcessError):
        return None


def _lane_library(functions: dict[str, ca.Function],
                  shared: dict[str, tuple[int, ...]] = SHARED_INPUTS) -> tuple[Path, bool, float] | None:
    """Build (or find in the cache) the lane-code library of ``functions`` (``shared``: their
    inputs shared by all frames): (path, was cached, compile seconds); None when some function
    has an operation without lane code."""
    width, isa_flags = lanes.isa()
    flags = (*LANE_CFLAGS, *isa_flags)
    try:
        sources = {name: lanes.header(width) + lanes.function_source(f, shared.get(name, ()))
                   for name, f in functions.items()}
    except NotImplementedError:
        return None
    digest = hashlib.sha256("".join(sources.values()).encode() + " ".join(flags).encode()).hexdigest()[:20]
    lib = cache_dir() / "lanes" / f"{digest}.so"
    if lib.is_file():
        return lib, True, 0.0
    t0 = time.perf_counter()
    try:
        _build_lanes(sources, flags, lib)
    except (OSError, subprocess.CalledProcessError):  # a compiler without vector extensions: casadi's C
        return None
    return lib, False, time.perf_counter() - t0


def _build_lanes(sources: dict[str, str], flags: tuple[str, ...], lib: Path) -> None:
    """Compile one object per function (in parallel) and link them into ``lib`` (atomically)."""
    lib.parent.mkdir(parents=True, exist_ok=True)
    cc = os.environ.get("CC", "gcc")
    with tempfile.TemporaryDirectory() as tmp:
        objs = []
        jobs = []
        for name, text in sources.items():
            src = Path(tmp) / f"{name}.c"
            src.write_text(text)
            objs.append(str(src.with_suffix(".o")))
            jobs.append([cc, *flags, "-c", str(src), "-o", objs[-1]])
        # the biggest files first, one compiler per core
        jobs.sort(key=lambda cmd: -Path(cmd[-3]).stat().st_size)
        with ThreadPoolExecutor(max_workers=max(1, min(len(jobs), os.cpu_count() or 1))) as pool:
            list(pool.map(_run, jobs))
        part = lib.with_name(lib.name + f".{os.getpid()}.tmp")
        _run([cc, "-shared", *objs, "-o", str(part), "-lm"])
        part.replace(lib)  # atomic: concurrent processes never load a half-written library


def _casadi_library(functions: dict[str, ca.Function]) -> tuple[Path, bool, float]:
    with tempfile.TemporaryDirectory() as tmp:
        gen = ca.CodeGenerator("m2r_problem.c", {"with_header": False})
        for f in functions.values():
            gen.add(f)
        src = Path(gen.generate(tmp + os.sep))
        digest = hashlib.sha256(src.read_bytes() + " ".join(CFLAGS).encode()).hexdigest()[:20]
        lib = cache_dir() / "casadi" / f"{digest}.so"
        cached = lib.is_file()
        t1 = time.perf_counter()
        if not cached:
            lib.parent.mkdir(parents=True, exist_ok=True)
            _compile(src, lib)
        return lib, cached, time.perf_counter() - t1


def _recipe_path(spec: ProblemSpec) -> Path:
    width, isa_flags = lanes.isa()
    build = " ".join((*LANE_CFLAGS, *isa_flags, f"lanes={width}"))
    return cache_dir() / "lanes" / f"recipe-{recipe_digest(spec, build)}.json"


def _recipe_lookup(recipe: Path) -> tuple[Path, dict] | None:
    """The library and signatures recorded under ``recipe``, if both are there and readable."""
    try:
        info = json.loads(recipe.read_text())
        lib = recipe.parent / Path(info["library"]).name
        sigs = {name: (str(c), [int(x) for x in nin], [int(x) for x in nout])
                for name, (c, nin, nout) in info["signatures"].items()}
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return (lib, sigs) if lib.is_file() and set(sigs) == set(FUNCTIONS) else None


def _recipe_record(recipe: Path, lib: Path, functions: dict[str, ca.Function]) -> None:
    info = {"library": lib.name, "signatures": {name: lanes.signature(f) for name, f in functions.items()}}
    write_atomic(recipe, json.dumps(info))  # a read-only cache: the next process builds the graph again


@functools.lru_cache(maxsize=8)
def compiled_problem(robot: Robot, backend: str = "auto") -> CompiledProblem:
    """The robot's problem, code-generated and compiled (cached on disk): ``backend`` "auto"
    (lane code, else casadi's C, else the virtual machine without a C compiler), or one of
    "lanes" / "c" / "vm"."""
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}; use one of {', '.join(BACKENDS)}")
    t0 = time.perf_counter()
    spec = build_spec(robot)
    no_compiler = backend == "vm" or (backend == "auto" and _compiler() is None)
    lane_code = backend in ("auto", "lanes") and not no_compiler
    recipe = _recipe_path(spec) if lane_code else None  # the digest reads every module's source
    if lane_code:
        found = _recipe_lookup(recipe)
        if found is not None:  # compiled before from the same recipe: no graph to build
            lib, sigs = found
            return CompiledProblem(spec, {}, "lanes", time.perf_counter() - t0, 0.0, True, ctypes.CDLL(str(lib)), sigs)
    functions = build_functions(spec)
    build_s = time.perf_counter() - t0
    if no_compiler:
        return CompiledProblem(spec, functions, "vm", build_s, 0.0, False)
    if lane_code:
        built = _lane_library(functions)
        if built is not None:
            lib, cached, compile_s = built
            _recipe_record(recipe, lib, functions)
            return CompiledProblem(spec, functions, "lanes", build_s, compile_s, cached, ctypes.CDLL(str(lib)))
        if backend == "lanes":
            raise ValueError("lane code cannot be generated for this robot's functions; use backend 'c'")
    try:
        lib, cached, compile_s = _casadi_library(functions)
    except (OSError, subprocess.CalledProcessError):
        if backend == "c":
            raise
        return CompiledProblem(spec, functions, "vm", build_s, 0.0, False)  # the compiler failed: same numbers, slower
    ext = {name: ca.external(f.name(), str(lib)) for name, f in functions.items()}
    return CompiledProblem(spec, ext, "c", build_s, compile_s, cached)

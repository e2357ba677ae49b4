"""Compile the problem's casadi functions to C once per robot and cache the shared library.

The generated C source is hashed; the library lives in ``$MOTION2ROBOT_CACHE`` (default
``~/.cache/motion2robot``) as ``casadi/<hash>.so``, so a second process (or a second run) only
loads it. When no C compiler is available the casadi virtual machine evaluates the same
functions (slower, same numbers).
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from motion2robot.retarget.problem import ProblemSpec, build_functions, build_spec
from motion2robot.robot.robot import Robot

CFLAGS = ("-O1", "-fPIC", "-shared")  # -O2 runs ~10 % faster but compiles ~2x longer


def cache_dir() -> Path:
    root = os.environ.get("MOTION2ROBOT_CACHE")
    return Path(root) if root else Path.home() / ".cache" / "motion2robot"


@dataclass(frozen=True, eq=False)
class CompiledProblem:
    """A robot's problem ready to evaluate: ``step``/``project``/``points`` casadi functions (compiled C when
    ``backend == "c"``), the spec, and how long building/compiling took (s)."""

    spec: ProblemSpec
    step: ca.Function
    project: ca.Function
    points: ca.Function
    backend: str
    build_s: float
    compile_s: float
    cached: bool

    @functools.lru_cache(maxsize=8)
    def step_eval(self, frames: int) -> MappedEval:
        """``step`` over ``frames`` frames in one call (the weights ``w`` shared by all frames)."""
        return MappedEval(self.step.map("m2r_step_map", "serial", frames, [2], []), frames)

    @functools.lru_cache(maxsize=8)
    def project_eval(self, frames: int) -> MappedEval:
        return MappedEval(self.project.map(frames, "serial"), frames)

    @functools.lru_cache(maxsize=8)
    def points_eval(self, frames: int) -> MappedEval:
        return MappedEval(self.points.map(frames, "serial"), frames)


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
        """Evaluate; each input is copied into its bound array; returns copies of the outputs."""
        for a, x in zip(self.args, inputs):
            a[...] = np.reshape(x, a.shape)
        self._eval()
        return [r.copy() for r in self.res]


def _compile(src: Path, out: Path) -> None:
    cc = os.environ.get("CC", "gcc")
    tmp = out.with_name(out.name + f".{os.getpid()}.tmp")
    subprocess.run([cc, *CFLAGS, str(src), "-o", str(tmp), "-lm"], check=True, capture_output=True)
    tmp.replace(out)  # atomic: concurrent processes never load a half-written library


@functools.lru_cache(maxsize=8)
def compiled_problem(robot: Robot, backend: str = "auto") -> CompiledProblem:
    """The robot's problem, code-generated and compiled (cached on disk) unless ``backend`` is
    ``"vm"`` or no C compiler is found."""
    t0 = time.perf_counter()
    spec = build_spec(robot)
    step, project, points = build_functions(spec)
    build_s = time.perf_counter() - t0
    if backend == "vm" or (backend == "auto" and shutil.which(os.environ.get("CC", "gcc")) is None):
        return CompiledProblem(spec, step, project, points, "vm", build_s, 0.0, False)
    with tempfile.TemporaryDirectory() as tmp:
        gen = ca.CodeGenerator("m2r_problem.c", {"with_header": False})
        for f in (step, project, points):
            gen.add(f)
        src = Path(gen.generate(tmp + os.sep))
        digest = hashlib.sha256(src.read_bytes() + " ".join(CFLAGS).encode()).hexdigest()[:20]
        lib = cache_dir() / "casadi" / f"{digest}.so"
        cached = lib.is_file()
        t1 = time.perf_counter()
        if not cached:
            lib.parent.mkdir(parents=True, exist_ok=True)
            _compile(src, lib)
        compile_s = time.perf_counter() - t1
    ext = [ca.external(f"m2r_{name}", str(lib)) for name in ("step", "project", "points")]
    return CompiledProblem(spec, *ext, "c", build_s, compile_s, cached)

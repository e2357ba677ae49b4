"""C code for casadi SX functions evaluated on several frames at once (frames as SIMD lanes).

casadi's own code generator emits one scalar statement per SX instruction: the step function of
a 20-joint robot is ~50,000 statements, i.e. several hundred kilobytes of straight-line machine
code run once per frame, limited by instruction fetch (about one operation per cycle). Here each
work slot is a vector of ``lanes`` doubles (GCC/Clang vector extension) holding that many frames,
so every instruction is one vector operation, ``w5 = w3 * w4``, on a block of frames: the code
is fetched once per block and each operation works on all its frames (op3 step: 17.7 -> 4.7
us/frame with 4 AVX2 lanes, same bits as casadi's virtual machine; ``scripts/bench_retarget.py``).

Generated from casadi's instruction list (:meth:`casadi.Function.instruction_id` and friends).
The work slots are local variables (the compiler's register allocator places them; a work array
made GCC's alias analysis take 2.5x longer). Operations without a vector form (sqrt, sin, ...)
run lane by lane. An operation missing from the tables raises :class:`NotImplementedError` (the
caller falls back to casadi's code generator).

Calling convention of a generated function ``NAME(int T, const double **arg, double **res)``:
input i is a (T, nnz_i) C-contiguous array, or (nnz_i,) shared by every frame when listed in
``shared``; output j is a (T, nnz_j) array (a NULL pointer skips it). Numbers are the same as
casadi's evaluation: floating-point contraction (FMA) is switched off.
"""

from __future__ import annotations

import ctypes
import platform
from pathlib import Path

import casadi as ca
import numpy as np

_BINARY = {
    ca.OP_ADD: "{a} + {b}", ca.OP_SUB: "{a} - {b}", ca.OP_MUL: "{a} * {b}", ca.OP_DIV: "{a} / {b}",
    ca.OP_LT: "TRUTH({a} < {b})", ca.OP_LE: "TRUTH({a} <= {b})", ca.OP_EQ: "TRUTH({a} == {b})",
    ca.OP_NE: "TRUTH({a} != {b})", ca.OP_AND: "TRUTH(({a} != 0) & ({b} != 0))",
    ca.OP_OR: "TRUTH(({a} != 0) | ({b} != 0))", ca.OP_IF_ELSE_ZERO: "KEEP({b}, {a} != 0)",
    # fmin/fmax as selects (they vectorise); they differ from C's only for NaN operands, which the
    # retargeter never passes (non-finite motions are refused before solving)
    ca.OP_FMIN: "SELECT({a} < {b}, {a}, {b})", ca.OP_FMAX: "SELECT({a} > {b}, {a}, {b})",
}
#: Operations done lane by lane through the C library (few in these functions).
_LANEWISE_UNARY = {
    ca.OP_SQRT: "sqrt", ca.OP_SIN: "sin", ca.OP_COS: "cos", ca.OP_TAN: "tan", ca.OP_EXP: "exp",
    ca.OP_LOG: "log", ca.OP_ATAN: "atan", ca.OP_ASIN: "asin", ca.OP_ACOS: "acos", ca.OP_TANH: "tanh",
    ca.OP_FABS: "fabs",
}
_LANEWISE_BINARY = {ca.OP_ATAN2: "atan2", ca.OP_POW: "pow", ca.OP_CONSTPOW: "pow", ca.OP_COPYSIGN: "copysign"}
_UNARY = {
    ca.OP_ASSIGN: "{a}", ca.OP_NEG: "-{a}", ca.OP_SQ: "{a} * {a}", ca.OP_TWICE: "{a} + {a}",
    ca.OP_INV: "1.0 / {a}", ca.OP_NOT: "TRUTH({a} == 0)",
    ca.OP_SIGN: "(TRUTH({a} > 0) - TRUTH({a} < 0))",
}

_HEADER = """#include <math.h>
#define L {lanes}
typedef double vd __attribute__((vector_size(8 * L), aligned(8 * L)));
typedef long long vl __attribute__((vector_size(8 * L), aligned(8 * L)));
static const vd ONE = {{{ones}}};
/* comparisons give lanes of -1 (true) / 0 (false) */
#define TRUTH(m) ((vd)((vl)ONE & (m)))
#define KEEP(x, m) ((vd)((vl)(x) & (m)))
#define SELECT(m, x, y) ((vd)(((m) & (vl)(x)) | (~(m) & (vl)(y))))
#define LANEWISE1(f, x) ({{ vd x_ = (x), r_; for (int k_ = 0; k_ < L; ++k_) r_[k_] = f(x_[k_]); r_; }})
#define LANEWISE2(f, x, y) ({{ vd x_ = (x), y_ = (y), r_; for (int k_ = 0; k_ < L; ++k_) r_[k_] = f(x_[k_], y_[k_]); r_; }})
"""


def isa() -> tuple[int, tuple[str, ...]]:
    """Lanes per vector and the compiler flags for this machine: 4 with AVX2 (x86-64 CPUs that
    have it), else 2 (SSE2 on x86-64, NEON on arm64: the baseline of both)."""
    if platform.machine().lower() in ("x86_64", "amd64"):
        try:
            flags = Path("/proc/cpuinfo").read_text().split("flags", 1)[1].split("\n", 1)[0].split()
        except (OSError, IndexError):
            flags = []
        if "avx2" in flags:
            return 4, ("-mavx2",)
    return 2, ()


def header(lanes: int) -> str:
    """The C declarations every generated file starts with."""
    return _HEADER.format(lanes=lanes, ones=", ".join(["1.0"] * lanes))


def function_source(f: ca.Function, shared: tuple[int, ...] = ()) -> str:
    """C source of ``f`` (an SX function) evaluated a block of frames at a time (module docstring);
    prefix it with :func:`header`."""
    name = f.name()
    if not all(f.sparsity_in(i).is_dense() for i in range(f.n_in())) or \
            not all(f.sparsity_out(i).is_dense() for i in range(f.n_out())):
        raise NotImplementedError(f"{name}: lane code needs dense inputs and outputs")
    nnz_in = [f.nnz_in(i) for i in range(f.n_in())]
    nnz_out = [f.nnz_out(i) for i in range(f.n_out())]
    body = []
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        ins, outs = f.instruction_input(k), f.instruction_output(k)
        o = f"w{outs[0]}" if op != ca.OP_OUTPUT else None
        a, b = (f"w{i}" for i in (list(ins) + [0, 0])[:2])
        if op == ca.OP_INPUT:
            i, nz = ins
            if i in shared:
                body.append(f"{o} = (vd){{}} + arg[{i}][{nz}];")
            else:
                body.append(f"for (k = 0; k < L; ++k) {o}[k] = x{i}[lane[k] * {nnz_in[i]} + {nz}];")
        elif op == ca.OP_OUTPUT:
            i, nz = outs
            body.append(f"if (res[{i}]) for (k = 0; k < nb; ++k) y{i}[k * {nnz_out[i]} + {nz}] = {a}[k];")
        elif op == ca.OP_CONST:
            body.append(f"{o} = (vd){{}} + {_literal(f.instruction_constant(k))};")
        elif op in _BINARY:
            body.append(f"{o} = {_BINARY[op].format(a=a, b=b)};")
        elif op in _UNARY:
            body.append(f"{o} = {_UNARY[op].format(a=a)};")
        elif op in _LANEWISE_UNARY:
            body.append(f"{o} = LANEWISE1({_LANEWISE_UNARY[op]}, {a});")
        elif op in _LANEWISE_BINARY:
            body.append(f"{o} = LANEWISE2({_LANEWISE_BINARY[op]}, {a}, {b});")
        else:
            raise NotImplementedError(f"{name}: casadi operation {op} has no lane code")
    decl_in = "".join(f"    const double *x{i} = arg[{i}] + t0 * {n};\n" for i, n in enumerate(nnz_in) if i not in shared)
    decl_out = "".join(f"    double *y{j} = res[{j}] ? res[{j}] + t0 * {n} : 0;\n" for j, n in enumerate(nnz_out))
    code = "\n    ".join(body)
    return f"""
void {name}(int T, const double **arg, double **res) {{
  int k, t0, lane[L];
  vd {", ".join(f"w{i}" for i in range(f.sz_w()))};
  for (t0 = 0; t0 < T; t0 += L) {{
    int nb = T - t0 < L ? T - t0 : L;
{decl_in}{decl_out}    for (k = 0; k < L; ++k) lane[k] = k < nb ? k : nb - 1;  /* a short last block repeats its last frame */
    {code}
  }}
}}
"""




def _literal(x: float) -> str:
    if np.isnan(x):
        return "NAN"
    if np.isinf(x):
        return "INFINITY" if x > 0 else "-INFINITY"
    return repr(float(x))


def signature(f: ca.Function) -> tuple[str, list[int], list[int]]:
    """(name, nonzeros of each input, of each output) of ``f``: all :class:`LaneEval` needs."""
    return f.name(), [f.nnz_in(i) for i in range(f.n_in())], [f.nnz_out(i) for i in range(f.n_out())]


class LaneEval:
    """Calls the generated function ``name`` of library ``lib`` (made from casadi function ``f``)
    on numpy arrays: each input (T, nnz_i) (or (nnz_i,) when shared), any shape that reshapes to
    it; returns the outputs as new (T, nnz_j) arrays."""

    def __init__(self, lib: ctypes.CDLL, f: ca.Function | tuple[str, list[int], list[int]],
                 shared: tuple[int, ...] = ()):
        """``f``: the casadi function, or its signature (name, input sizes, output sizes) as
        :func:`signature` gives it."""
        name, self.nnz_in, self.nnz_out = signature(f) if isinstance(f, ca.Function) else f
        self._fn = getattr(lib, name)
        self._fn.argtypes = [ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p]  # double **, as addresses
        self._fn.restype = None
        self.name = name
        self.shared = shared

    def __call__(self, *inputs: np.ndarray) -> list[np.ndarray]:
        if len(inputs) != len(self.nnz_in):
            raise TypeError(f"{self.name} takes {len(self.nnz_in)} inputs, got {len(inputs)}")
        frames = next(len(x) for i, x in enumerate(inputs) if i not in self.shared)
        args = []
        for i, (x, n) in enumerate(zip(inputs, self.nnz_in)):
            shape = (n,) if i in self.shared else (frames, n)
            args.append(np.ascontiguousarray(np.reshape(x, shape), dtype=np.float64))
        outs = [np.empty((frames, n)) for n in self.nnz_out]
        if frames:
            arg_ptrs = np.array([a.ctypes.data for a in args], dtype=np.uintp)
            out_ptrs = np.array([o.ctypes.data for o in outs], dtype=np.uintp)
            self._fn(frames, arg_ptrs.ctypes.data, out_ptrs.ctypes.data)
        return outs

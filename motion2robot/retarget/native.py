"""Two sequential loops over the frames, in C: the pentadiagonal solve of the smoothing
(:mod:`~motion2robot.retarget.smoothing`) and the forward-backward velocity clamp
(:mod:`~motion2robot.retarget.constraints`). Python loops over the frames cost more than the rest
of the retargeting; these kernels are compiled once (cached beside the casadi library, see
:mod:`~motion2robot.retarget.compiled`) and loaded with ctypes. Without a C compiler the callers
fall back to their numpy versions (same numbers).
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np

SOURCE = r"""
#include <math.h>
/* A x = b, A symmetric positive definite pentadiagonal per column j of k columns; arrays are
   row-major (T, k): d0 diagonal, d1 first (T-1 rows), d2 second (T-2 rows) super-diagonal.
   b is overwritten with x; l0, l1, l2, work (T, k) scratch. */
void m2r_penta_solve(int T, int k, const double *d0, const double *d1, const double *d2, double *b,
                     double *l0, double *l1, double *l2) {
    for (int j = 0; j < k; ++j) {
        for (int t = 0; t < T; ++t) {
            double s = d0[t * k + j], r = b[t * k + j], a2 = 0.0, a1 = 0.0;
            if (t >= 2) {
                a2 = d2[(t - 2) * k + j] / l0[(t - 2) * k + j];
                s -= a2 * a2;
                r -= a2 * b[(t - 2) * k + j];
            }
            if (t >= 1) {
                a1 = (d1[(t - 1) * k + j] - (t >= 2 ? a2 * l1[(t - 1) * k + j] : 0.0)) / l0[(t - 1) * k + j];
                s -= a1 * a1;
                r -= a1 * b[(t - 1) * k + j];
            }
            l2[t * k + j] = a2;
            l1[t * k + j] = a1;
            l0[t * k + j] = sqrt(s);
            b[t * k + j] = r / l0[t * k + j];
        }
        for (int t = T - 1; t >= 0; --t) {
            double r = b[t * k + j];
            if (t + 1 < T) r -= l1[(t + 1) * k + j] * b[(t + 1) * k + j];
            if (t + 2 < T) r -= l2[(t + 2) * k + j] * b[(t + 2) * k + j];
            b[t * k + j] = r / l0[t * k + j];
        }
    }
}

/* |q[t+1] - q[t]| <= step for every t: forward pass, then backward pass; q (T, n) row-major. */
void m2r_clamp_velocity(int T, int n, double *q, const double *step) {
    for (int t = 1; t < T; ++t)
        for (int j = 0; j < n; ++j) {
            double lo = q[(t - 1) * n + j] - step[j], hi = q[(t - 1) * n + j] + step[j], *x = &q[t * n + j];
            *x = *x < lo ? lo : (*x > hi ? hi : *x);
        }
    for (int t = T - 2; t >= 0; --t)
        for (int j = 0; j < n; ++j) {
            double lo = q[(t + 1) * n + j] - step[j], hi = q[(t + 1) * n + j] + step[j], *x = &q[t * n + j];
            *x = *x < lo ? lo : (*x > hi ? hi : *x);
        }
}
"""

_DP = ctypes.POINTER(ctypes.c_double)


@functools.lru_cache(maxsize=1)
def library() -> ctypes.CDLL | None:
    """The compiled kernels (built on first use, cached on disk), or None without a working C
    compiler (or with ``MOTION2ROBOT_NATIVE=0``)."""
    from motion2robot.retarget.compiled import CFLAGS, _compile, cache_dir

    if os.environ.get("MOTION2ROBOT_NATIVE", "1") == "0" or shutil.which(os.environ.get("CC", "gcc")) is None:
        return None
    digest = hashlib.sha256((SOURCE + " ".join(CFLAGS)).encode()).hexdigest()[:20]
    lib = cache_dir() / "native" / f"{digest}.so"
    try:
        if not lib.is_file():
            lib.parent.mkdir(parents=True, exist_ok=True)
            src = lib.with_name(f"{digest}.{os.getpid()}.c")
            src.write_text(SOURCE)
            try:
                _compile(Path(src), lib)
            finally:
                src.unlink(missing_ok=True)
        dll = ctypes.CDLL(str(lib))
    except (OSError, subprocess.CalledProcessError):  # no usable compiler / unwritable cache: numpy it is
        return None
    dll.m2r_penta_solve.argtypes = [ctypes.c_int, ctypes.c_int] + [_DP] * 7
    dll.m2r_penta_solve.restype = None
    dll.m2r_clamp_velocity.argtypes = [ctypes.c_int, ctypes.c_int, _DP, _DP]
    dll.m2r_clamp_velocity.restype = None
    return dll


def _ptr(a: np.ndarray):
    return a.ctypes.data_as(_DP)


def penta_solve(d0: np.ndarray, d1: np.ndarray, d2: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """C version of :func:`~motion2robot.retarget.smoothing.pentadiagonal_solve` (same arguments);
    None when the kernels are not available."""
    dll = library()
    if dll is None:
        return None
    T, k = b.shape
    args = [np.ascontiguousarray(a, dtype=np.float64) for a in (d0, d1, d2)]
    x = np.array(b, dtype=np.float64, order="C")
    scratch = [np.empty((T, k)) for _ in range(3)]
    dll.m2r_penta_solve(T, k, *(_ptr(a) for a in args), _ptr(x), *(_ptr(s) for s in scratch))
    return x


def clamp_velocity(q: np.ndarray, step: np.ndarray) -> np.ndarray | None:
    """C version of the forward-backward clamp of (T, n) ``q`` to ``|q[t+1]-q[t]| <= step`` (n,);
    returns a new array, or None when the kernels are not available."""
    dll = library()
    if dll is None:
        return None
    out = np.array(q, dtype=np.float64, order="C")
    s = np.ascontiguousarray(np.broadcast_to(step, out.shape[1:]), dtype=np.float64)
    dll.m2r_clamp_velocity(out.shape[0], out.shape[1], _ptr(out), _ptr(s))
    return out

"""Sequential loops over the frames, in C: the pentadiagonal solve of the smoothing and its
reweighting loop (:mod:`~motion2robot.retarget.smoothing`), the forward-backward velocity clamp
(:mod:`~motion2robot.retarget.constraints`), and the root-quaternion arithmetic of the solver's
steps (:func:`~motion2robot.retarget.problem.apply_step`,
:func:`~motion2robot.retarget.problem.tangent_diff`: ~30 small numpy operations per call on a
few hundred frames, called every iteration). Python loops over the frames cost more than the rest
of the retargeting; these kernels are compiled once (cached beside the casadi library, see
:mod:`~motion2robot.retarget.compiled`) and loaded with ctypes. Without a C compiler the callers
fall back to their numpy versions (same numbers).
"""

from __future__ import annotations

import ctypes
import functools

import numpy as np

SOURCE = r"""
#include <math.h>
/* A x = b, A symmetric positive definite pentadiagonal per column j of k columns; arrays are
   row-major (T, k): d0 diagonal, d1 first (T-1 rows), d2 second (T-2 rows) super-diagonal.
   b is overwritten with x; l0, l1, l2, work (T, k) scratch. */
static void penta_column(int T, int k, int j, const double *d0, const double *d1, const double *d2, double *b,
                         double *l0, double *l1, double *l2) {
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

void m2r_penta_solve(int T, int k, const double *d0, const double *d1, const double *d2, double *b,
                     double *l0, double *l1, double *l2) {
    for (int j = 0; j < k; ++j) penta_column(T, k, j, d0, d1, d2, b, l0, l1, l2);
}

/* The reweighting loop of smoothing.smooth_to_targets, same steps: y (T, k) starts as r; while
   some |diff y| / vstep or |diff2 y| / astep exceeds 1 (over all columns), raise the weights u
   (T-1, k) and m (T-2, k) of those rows and solve the pentadiagonal system again. A column whose
   weights did not change keeps its solution (the same system), so only the others are solved.
   scratch: 8 T k doubles. */
void m2r_smooth_irls(int T, int k, const double *r, const double *vstep, const double *astep,
                     int iterations, double *y, double *scratch) {
    double *u = scratch, *m = u + T * k, *d0 = m + T * k, *d1 = d0 + T * k, *d2 = d1 + T * k;
    double *l0 = d2 + T * k, *l1 = l0 + T * k, *l2 = l1 + T * k;
    for (int i = 0; i < T * k; ++i) { y[i] = r[i]; u[i] = 0.0; m[i] = 0.0; }
    for (int it = 0; it < iterations; ++it) {
        int any = 0;
        for (int j = 0; j < k; ++j) {
            int changed = 0;
            for (int t = 0; t + 1 < T; ++t) {
                double rv = fabs(y[(t + 1) * k + j] - y[t * k + j]) / vstep[j];
                if (rv > 1.0) { u[t * k + j] = (u[t * k + j] + 1.0) * rv * rv; changed = 1; }
                if (t + 2 < T) {
                    double ra = fabs(y[(t + 2) * k + j] - 2.0 * y[(t + 1) * k + j] + y[t * k + j]) / astep[j];
                    if (ra > 1.0) { m[t * k + j] = (m[t * k + j] + 1.0) * ra * ra; changed = 1; }
                }
            }
            if (!changed) continue;
            any = 1;
            for (int t = 0; t < T; ++t) {
                d0[t * k + j] = 1.0; d1[t * k + j] = 0.0; d2[t * k + j] = 0.0; y[t * k + j] = r[t * k + j];
            }
            for (int t = 0; t + 1 < T; ++t) {
                double a = u[t * k + j];
                d0[t * k + j] += a; d0[(t + 1) * k + j] += a; d1[t * k + j] -= a;
                if (t + 2 < T) {
                    double b = m[t * k + j];
                    d0[t * k + j] += b; d0[(t + 1) * k + j] += 4.0 * b; d0[(t + 2) * k + j] += b;
                    d1[t * k + j] -= 2.0 * b; d1[(t + 1) * k + j] -= 2.0 * b; d2[t * k + j] += b;
                }
            }
            penta_column(T, k, j, d0, d1, d2, y, l0, l1, l2);
        }
        if (!any) break;
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

/* Hamilton product o = a b of wxyz quaternions, in the order of problem.quat_mul. */
static void quat_mul(const double *a, const double *b, double *o) {
    o[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    o[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    o[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    o[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

/* problem.apply_step: q (T, nq) moved by dx (T, nq - 1) into out (T, nq). */
void m2r_apply_step(int T, int nq, const double *q, const double *dx, double *out) {
    int nv = nq - 1;
    for (int t = 0; t < T; ++t) {
        const double *a = q + t * nq, *d = dx + t * nv;
        double *o = out + t * nq, b[4], r[4];
        for (int i = 0; i < 3; ++i) o[i] = a[i] + d[i];
        double ang = sqrt(d[3] * d[3] + d[4] * d[4] + d[5] * d[5]), half = 0.5 * ang;
        double s = ang > 1e-12 ? sin(half) / fmax(ang, 1e-12) : 0.5;
        b[0] = cos(half); b[1] = s * d[3]; b[2] = s * d[4]; b[3] = s * d[5];
        quat_mul(a + 3, b, r);
        double n = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3]);
        for (int i = 0; i < 4; ++i) o[3 + i] = r[i] / n;
        for (int i = 7; i < nq; ++i) o[i] = a[i] + d[i - 1];
    }
}

/* problem.tangent_diff: d (T, nq - 1) = a - b (T, nq), the root rotation as the rotation vector
   of conj(b) a. */
void m2r_tangent_diff(int T, int nq, const double *a, const double *b, double *d) {
    int nv = nq - 1;
    for (int t = 0; t < T; ++t) {
        const double *x = a + t * nq, *y = b + t * nq;
        double *o = d + t * nv, c[4] = {y[3], -y[4], -y[5], -y[6]}, r[4];
        for (int i = 0; i < 3; ++i) o[i] = x[i] - y[i];
        quat_mul(c, x + 3, r);
        if (r[0] < 0) for (int i = 0; i < 4; ++i) r[i] = -r[i];
        double s = sqrt(r[1] * r[1] + r[2] * r[2] + r[3] * r[3]), ang = 2 * atan2(s, r[0]);
        for (int i = 0; i < 3; ++i) o[3 + i] = s > 1e-12 ? r[1 + i] * ang / fmax(s, 1e-12) : 2 * r[1 + i];
        for (int i = 7; i < nq; ++i) o[i - 1] = x[i] - y[i];
    }
}

static double clip01(double x) { x = x >= 0.0 ? x : 0.0; return x <= 1.0 ? x : 1.0; }

/* anchor_gap.segment_distance of the 2D segments pq and ab, the same operations in the same order. */
static double segment_distance(const double *p, const double *q, const double *a, const double *b) {
    double d1x = q[0] - p[0], d1y = q[1] - p[1], d2x = b[0] - a[0], d2y = b[1] - a[1];
    double rx = p[0] - a[0], ry = p[1] - a[1];
    double aa = (d1x * d1x + d1y * d1y) + 1e-12, ee = (d2x * d2x + d2y * d2y) + 1e-12, ff = d2x * rx + d2y * ry;
    double c = d1x * rx + d1y * ry, bb = d1x * d2x + d1y * d2y;
    double den = aa * ee - bb * bb;
    den = den >= 1e-12 ? den : 1e-12;
    double s = clip01((bb * ff - c * ee) / den);
    double t = (bb * s + ff) / ee;
    if (t < 0) s = clip01(-c / aa);
    else if (t > 1) s = clip01((bb - c) / aa);
    t = clip01(t);
    double x = p[0] + s * d1x - a[0] - t * d2x, y = p[1] + s * d1y - a[1] - t * d2y;
    return sqrt(x * x + y * y);
}

/* anchor_gap._push: the move (2) of segment seg (2, 2) from the grid moves (S, D, 2), the shortest
   length first, then the direction with the largest gap, after which seg is `need` from other. */
void m2r_push(const double *seg, const double *other, double need, int S, int D, const double *moves, double *out) {
    out[0] = 0.0; out[1] = 0.0;
    if (segment_distance(seg, seg + 2, other, other + 2) >= need) return;
    for (int k = 0; k < S; ++k) {
        int best = 0, ok = 0;
        double top = 0.0;
        for (int j = 0; j < D; ++j) {
            const double *m = moves + 2 * (k * D + j);
            double p[2] = {seg[0] + m[0], seg[1] + m[1]}, q[2] = {seg[2] + m[0], seg[3] + m[1]};
            double g = segment_distance(p, q, other, other + 2);
            if (j == 0 || g > top) { top = g; best = j; }
            ok |= g >= need;
        }
        if (ok || k == S - 1) {
            out[0] = moves[2 * (k * D + best)];
            out[1] = moves[2 * (k * D + best) + 1];
            return;
        }
    }
}
"""

#: double * arguments, passed as the arrays' addresses (``data_as`` casts cost more than the
#: small kernels they call).
_DP = ctypes.c_void_p


@functools.lru_cache(maxsize=1)
def library() -> ctypes.CDLL | None:
    """The compiled kernels (built on first use, cached on disk), or None without a working C
    compiler (or with ``MOTION2ROBOT_NATIVE=0``)."""
    from motion2robot.retarget.compiled import cached_library

    dll = cached_library("kernels", SOURCE)
    if dll is None:  # no usable compiler / unwritable cache: numpy it is
        return None
    dll.m2r_penta_solve.argtypes = [ctypes.c_int, ctypes.c_int] + [_DP] * 7
    dll.m2r_penta_solve.restype = None
    dll.m2r_smooth_irls.argtypes = [ctypes.c_int, ctypes.c_int, _DP, _DP, _DP, ctypes.c_int, _DP, _DP]
    dll.m2r_smooth_irls.restype = None
    dll.m2r_clamp_velocity.argtypes = [ctypes.c_int, ctypes.c_int, _DP, _DP]
    dll.m2r_clamp_velocity.restype = None
    dll.m2r_push.argtypes = [_DP, _DP, ctypes.c_double, ctypes.c_int, ctypes.c_int, _DP, _DP]
    dll.m2r_push.restype = None
    for name in ("m2r_apply_step", "m2r_tangent_diff"):
        getattr(dll, name).argtypes = [ctypes.c_int, ctypes.c_int, _DP, _DP, _DP]
        getattr(dll, name).restype = None
    return dll


def _ptr(a: np.ndarray) -> int:
    """The address of C-contiguous float64 ``a`` (kept alive by the caller during the call)."""
    return a.ctypes.data


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


def smooth_irls(r: np.ndarray, vstep: np.ndarray, astep: np.ndarray, iterations: int) -> np.ndarray | None:
    """C version of the reweighting loop of
    :func:`~motion2robot.retarget.smoothing.smooth_to_targets` on (T, k) ``r`` with (k,) step
    targets; returns the smoothed (T, k) array, or None when the kernels are not available."""
    dll = library()
    if dll is None:
        return None
    T, k = r.shape
    src = np.ascontiguousarray(r, dtype=np.float64)
    vs, as_ = (np.ascontiguousarray(np.broadcast_to(a, (k,)), dtype=np.float64) for a in (vstep, astep))
    y = np.empty((T, k))
    scratch = np.empty(8 * T * k)
    dll.m2r_smooth_irls(T, k, _ptr(src), _ptr(vs), _ptr(as_), iterations, _ptr(y), _ptr(scratch))
    return y


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


def _pairwise(name: str, a: np.ndarray, b: np.ndarray, width: int) -> np.ndarray | None:
    """Run kernel ``name`` on (T, nq) ``a`` and (T, *) ``b`` into a new (T, width) array."""
    dll = library()
    if dll is None:
        return None
    x, y = (np.ascontiguousarray(v, dtype=np.float64) for v in (a, b))
    out = np.empty((x.shape[0], width))
    getattr(dll, name)(x.shape[0], x.shape[1], _ptr(x), _ptr(y), _ptr(out))
    return out


def apply_step(qpos: np.ndarray, dx: np.ndarray) -> np.ndarray | None:
    """C version of :func:`~motion2robot.retarget.problem.apply_step`, or None without the kernels."""
    return _pairwise("m2r_apply_step", qpos, dx, qpos.shape[1])


def tangent_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """C version of :func:`~motion2robot.retarget.problem.tangent_diff`, or None without the kernels."""
    return _pairwise("m2r_tangent_diff", a, b, a.shape[1] - 1)


def push(seg: np.ndarray, other: np.ndarray, need: float, moves: np.ndarray) -> np.ndarray | None:
    """C version of :func:`~motion2robot.retarget.anchor_gap._push` over the grid ``moves`` (S, D, 2),
    or None without the kernels."""
    dll = library()
    if dll is None:
        return None
    a, b, m = (np.ascontiguousarray(x, dtype=np.float64) for x in (seg, other, moves))
    out = np.zeros(2)
    dll.m2r_push(_ptr(a), _ptr(b), float(need), m.shape[0], m.shape[1], _ptr(m), _ptr(out))
    return out

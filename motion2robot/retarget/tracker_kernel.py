"""The frame loop of :class:`~motion2robot.retarget.leg_tracker.LegTracker` in C.

The tracker's Levenberg-Marquardt takes about three iterations per frame, each a MuJoCo
kinematics pass, eight site Jacobians, the CoM Jacobian and a Cholesky solve: ~9 us of MuJoCo and
~27 us of Python around it. Here the same loop (same steps, same MuJoCo functions, the same
order of operations, so the same numbers) runs in C on the tracker's ``MjModel``/``MjData``
(:mod:`~motion2robot.util.mujoco_c`); where it cannot be built, the tracker runs its Python loop.
"""

from __future__ import annotations

import ctypes
import functools

import mujoco
import numpy as np

from motion2robot.util import mujoco_c

SOURCE = r"""
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <mujoco/mujoco.h>

#define HARD 26  /* rows of the targets: 8 sole corners x 3, the CoM's x and y */

/* ints: nq, nv, n legs, root body, zones apart, iterations; the leg hinges' qpos addresses
   (n), the unknowns' dof columns (6 + n), the 8 sole corner sites.
   c: limit gain, step tolerance, least cost gain, damping, largest step, hard weight, lost. */
typedef struct {
  const mjModel *m; mjData *d;
  int nq, nv, n, nc, rows, root, apart;
  const int *legq, *cols, *sites;
  const double *lo, *hi, *lo_zone, *hi_zone, *w;
  double gain;
  double *J, *jac;
} Tracker;

/* The rows at d->qpos into r (see LegTracker._residual); returns the cost. */
static double residual(Tracker *k, double *r, const double *corners, const double *com, double plan_z,
                       const double *plan_quat, const double *prev) {
  const mjModel *m = k->m; mjData *d = k->d;
  const double *q = d->qpos;
  int n = k->n, nc = k->nc, first = HARD + 4 + n;
  mj_kinematics(m, d);
  mj_comPos(m, d);
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 3; ++j) r[3 * i + j] = d->site_xpos[3 * k->sites[i] + j] - corners[3 * i + j];
  for (int j = 0; j < 2; ++j) r[24 + j] = d->subtree_com[3 * k->root + j] - com[j];
  r[26] = q[2] - plan_z;
  mju_subQuat(r + 27, q + 3, plan_quat);
  for (int i = 0; i < n; ++i) {
    double x = q[k->legq[i]], over;
    if (k->apart) {
      double c = x >= k->lo_zone[i] ? x : k->lo_zone[i];
      c = c <= k->hi_zone[i] ? c : k->hi_zone[i];
      over = x - c;
    } else {
      double t1 = x - k->hi_zone[i], t2 = k->lo_zone[i] - x;
      t1 = t1 >= 0.0 ? t1 : 0.0;
      t2 = t2 >= 0.0 ? t2 : 0.0;
      over = t1 - t2;
    }
    double jl = fabs(over) * k->gain;
    k->J[(30 + i) * nc + 6 + i] = jl;
    r[30 + i] = over * jl;
  }
  if (!prev) {
    for (int i = 0; i < first; ++i) r[i] *= k->w[i];
    return mju_dot(r, r, first);
  }
  for (int j = 0; j < 3; ++j) r[first + j] = q[j] - prev[j];
  mju_subQuat(r + first + 3, q + 3, prev + 3);
  for (int i = 0; i < n; ++i) r[first + 6 + i] = q[k->legq[i]] - prev[k->legq[i]];
  for (int i = 0; i < k->rows; ++i) r[i] *= k->w[i];
  return mju_dot(r, r, k->rows);
}

/* H = J^T J and g = -J^T r over the first `rows` rows, at the kinematics in d. */
static void normal(Tracker *k, const double *r, int rows, double *H, double *g) {
  const mjModel *m = k->m; mjData *d = k->d;
  int nv = k->nv, nc = k->nc;
  for (int i = 0; i < 8; ++i) mj_jacSite(m, d, k->jac + 3 * i * nv, NULL, k->sites[i]);
  mj_jacSubtreeCom(m, d, k->jac + 24 * nv, k->root);
  for (int i = 0; i < HARD; ++i)
    for (int c = 0; c < nc; ++c) k->J[i * nc + c] = k->jac[i * nv + k->cols[c]] * k->w[i];
  mju_mulMatTMat(H, k->J, k->J, rows, nc, nc);
  mju_mulMatTVec(g, k->J, r, rows, nc);
  for (int c = 0; c < nc; ++c) g[c] = -g[c];
}

static void factor(int nc, const double *H, double mu, const unsigned char *held, double *L) {
  memcpy(L, H, sizeof(double) * nc * nc);
  for (int i = 0; i < nc; ++i) L[i * nc + i] += mu;
  if (held) {
    for (int i = 0; i < nc; ++i)
      if (held[i])
        for (int j = 0; j < nc; ++j) { L[i * nc + j] = 0.0; L[j * nc + i] = 0.0; }
    for (int i = 0; i < nc; ++i) if (held[i]) L[i * nc + i] = 1.0;
  }
  mju_cholFactor(L, nc, 0.0);
}

/* The damped step into dx (see LegTracker._direction); returns its largest entry's size. */
static double direction(Tracker *k, const double *H, const double *g, double mu, const unsigned char *at_lo,
                        const unsigned char *at_hi, double *L, double *dx, unsigned char *held, double *rhs,
                        double max_step) {
  int nc = k->nc, n = k->n;
  factor(nc, H, mu, NULL, L);
  mju_cholSolve(dx, L, g, nc);
  if (at_lo) {
    memset(held, 0, nc);
    for (int it = 0; it < 2; ++it) {
      int out = 0;
      for (int i = 0; i < n; ++i) {
        int o = (at_lo[i] && dx[6 + i] < 0) || (at_hi[i] && dx[6 + i] > 0);
        if (o) { held[6 + i] = 1; ++out; }
      }
      if (!out) break;
      factor(nc, H, mu, held, L);
      for (int i = 0; i < nc; ++i) rhs[i] = held[i] ? 0.0 : g[i];
      mju_cholSolve(dx, L, rhs, nc);
    }
  }
  double big = 0.0;
  for (int i = 0; i < nc; ++i) { double a = fabs(dx[i]); big = a > big ? a : big; }
  if (big > max_step) {
    double s = max_step / big;
    for (int i = 0; i < nc; ++i) dx[i] *= s;
    big = max_step;
  }
  return big;
}

static void step(Tracker *k, const double *q, const double *dx) {
  double *p = k->d->qpos;
  memcpy(p, q, sizeof(double) * k->nq);
  for (int j = 0; j < 3; ++j) p[j] += dx[j];
  mju_quatIntegrate(p + 3, dx + 3, 1.0);
  for (int i = 0; i < k->n; ++i) {
    double x = q[k->legq[i]] + dx[6 + i];
    x = x >= k->lo[i] ? x : k->lo[i];
    p[k->legq[i]] = x <= k->hi[i] ? x : k->hi[i];
  }
}

/* LegTracker.solve's frame loop: out (T, nq) holds Q on entry and the solution on return; err (T).
   Returns 0, or -1 when its work memory cannot be allocated (nothing done). */
int m2r_track(const mjModel *m, mjData *d, int T, const int *ints, const int *legq, const int *cols,
               const int *sites, const double *lo, const double *hi, const double *lo_zone, const double *hi_zone,
               const double *w, const double *c, double *J, const double *Q, const double *start,
               const double *targets, const double *com_xy, double *out, double *err) {
  Tracker k = {m, d, ints[0], ints[1], ints[2], 6 + ints[2], 0, ints[3], ints[4], legq, cols, sites,
               lo, hi, lo_zone, hi_zone, w, c[0], J, NULL};
  int nq = k.nq, nc = k.nc, n = k.n, iterations = ints[5];
  k.rows = HARD + 4 + n + nc;
  double tol = c[1], least = c[2], damping = c[3], max_step = c[4], hard = c[5], lost = c[6];
  double *buf = malloc(sizeof(double) * (27 * k.nv + 2 * k.rows + 3 * nc * nc + 3 * nc + nq));
  k.jac = buf;
  double *r = k.jac + 27 * k.nv, *r_new = r + k.rows, *H = r_new + k.rows, *L = H + nc * nc;
  double *g = L + nc * nc, *dx = g + nc, *rhs = dx + nc, *q = rhs + nc;
  unsigned char *held = calloc(nc + 2 * n + 1, 1);
  if (!buf || !held) { free(buf); free(held); return -1; }
  unsigned char *at_lo = held + nc, *at_hi = at_lo + n;
  for (int t = 0; t < T; ++t) {
    const double *prev = t ? out + (t - 1) * nq : NULL;
    memcpy(q, Q + t * nq, sizeof(double) * nq);
    if (start) {
      memcpy(q, start + t * nq, sizeof(double) * 7);
      for (int i = 0; i < n; ++i) q[legq[i]] = start[t * nq + legq[i]];
    } else if (t) {
      q[0] = prev[0]; q[1] = prev[1];
      for (int i = 0; i < n; ++i) q[legq[i]] = prev[legq[i]];
    }
    int rows = t ? k.rows : HARD + 4 + n;
    const double *tg = targets + 24 * t, *cm = com_xy + 2 * t, *pq = Q + t * nq + 3;
    double pz = Q[t * nq + 2];
    memcpy(d->qpos, q, sizeof(double) * nq);
    double cost = residual(&k, r, tg, cm, pz, pq, prev), mu = damping;
    int fresh = 0, limit = 0;
    for (int it = 0; it < iterations; ++it) {
      if (!fresh) {
        normal(&k, r, rows, H, g);
        limit = 0;
        for (int i = 0; i < n; ++i) {
          at_lo[i] = q[legq[i]] <= lo[i] + 1e-9;
          at_hi[i] = q[legq[i]] >= hi[i] - 1e-9;
          limit |= at_lo[i] | at_hi[i];
        }
        fresh = 1;
      }
      double big = direction(&k, H, g, mu, limit ? at_lo : NULL, at_hi, L, dx, held, rhs, max_step);
      step(&k, q, dx);
      double c_new = residual(&k, r_new, tg, cm, pz, pq, prev);
      if (c_new < cost) {
        int done = big < tol || cost - c_new < least;
        memcpy(q, d->qpos, sizeof(double) * nq);
        double *s = r; r = r_new; r_new = s;
        cost = c_new;
        mu = mu / 10.0 > damping ? mu / 10.0 : damping;
        fresh = 0;
        if (done) break;
      } else {
        mu *= 100.0;
      }
    }
    double e = 0.0;
    for (int i = 0; i < HARD; ++i) { double a = fabs(r[i]); e = a > e ? a : e; }
    err[t] = e / hard;
    memcpy(out + t * nq, q, sizeof(double) * nq);
    if (err[t] > lost) {
      for (int s = t + 1; s < T; ++s) err[s] = err[t];
      break;
    }
  }
  free(buf);
  free(held);
  return 0;
}
"""

@functools.lru_cache(maxsize=1)
def library() -> ctypes.CDLL | None:
    """The compiled loop, or None where it cannot be built (:func:`~motion2robot.util.mujoco_c.load`)."""
    dll = mujoco_c.load("tracker", SOURCE)
    if dll is not None:
        dll.m2r_track.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int] + [ctypes.c_void_p] * 17
        dll.m2r_track.restype = ctypes.c_int
    return dll


def track(model: mujoco.MjModel, data: mujoco.MjData, ints: np.ndarray, legq: np.ndarray, cols: np.ndarray,
          sites: np.ndarray, limits: tuple[np.ndarray, ...], weights: np.ndarray, consts: np.ndarray,
          J: np.ndarray, Q: np.ndarray, start: np.ndarray | None, targets: np.ndarray,
          com_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The frame loop of ``LegTracker.solve`` in C (the arguments as it lays them out: int32
    and float64 C-contiguous arrays; ``limits`` = (lo, hi, lo_zone, hi_zone)); returns (out,
    err), or None when the library is not available or its work memory cannot be allocated."""
    dll = library()
    if dll is None:
        return None
    out = np.array(Q, dtype=np.float64, order="C")
    err = np.zeros(len(Q))
    q = np.ascontiguousarray(Q, dtype=np.float64)
    s = None if start is None else np.ascontiguousarray(start, dtype=np.float64)
    tg = np.ascontiguousarray(targets, dtype=np.float64)
    cm = np.ascontiguousarray(com_xy, dtype=np.float64)
    status = dll.m2r_track(model._address, data._address, len(Q), *(mujoco_c.address(a) for a in (
        ints, legq, cols, sites, *limits, weights, consts, J, q, s, tg, cm, out, err)))
    return (out, err) if status == 0 else None

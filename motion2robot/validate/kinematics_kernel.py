"""The frame loop of :func:`~motion2robot.validate.kinematics.compute_kinematics` in C: the same
MuJoCo calls per frame (``mj_kinematics``, ``mj_comPos``, ``mj_comVel``, ``mj_rne``, optionally
``mj_collision``) and the same copies, without Python between them
(:mod:`~motion2robot.util.mujoco_c`; None where it cannot be built: the caller loops in Python).
"""

from __future__ import annotations

import ctypes
import functools

import mujoco
import numpy as np

from motion2robot.util import mujoco_c

SOURCE = r"""
#include <string.h>
#include <mujoco/mujoco.h>

/* Per frame t: qpos, qvel, qacc (T, nq / nv) into d, the passes, then the copies into the (T, ...)
   outputs; with `collisions`, every contact as (frame, geom1, geom2, dist) while there is room for
   `cap`. Returns the number of contacts, or -1 when there were more than cap. */
int m2r_kinematics(const mjModel *m, mjData *d, int T, const double *qpos, const double *qvel,
                   const double *qacc, int collisions, double *site_xpos, double *xanchor, double *xaxis,
                   double *subtree_com, double *xpos, double *xmat, double *rne, int cap, int *con_frame,
                   int *con_geom, double *con_dist) {
  int nq = m->nq, nv = m->nv, count = 0;
  size_t ns = sizeof(double) * 3 * m->nsite, nj = sizeof(double) * 3 * m->njnt, nb = sizeof(double) * 3 * m->nbody;
  for (int t = 0; t < T; ++t) {
    memcpy(d->qpos, qpos + (size_t)t * nq, sizeof(double) * nq);
    memcpy(d->qvel, qvel + (size_t)t * nv, sizeof(double) * nv);
    memcpy(d->qacc, qacc + (size_t)t * nv, sizeof(double) * nv);
    mj_kinematics(m, d);
    mj_comPos(m, d);
    mj_comVel(m, d);
    mj_rne(m, d, 1, rne + (size_t)t * nv);
    if (collisions) mj_collision(m, d);
    memcpy(site_xpos + (size_t)t * 3 * m->nsite, d->site_xpos, ns);
    memcpy(xanchor + (size_t)t * 3 * m->njnt, d->xanchor, nj);
    memcpy(xaxis + (size_t)t * 3 * m->njnt, d->xaxis, nj);
    memcpy(subtree_com + (size_t)t * 3 * m->nbody, d->subtree_com, nb);
    memcpy(xpos + (size_t)t * 3 * m->nbody, d->xpos, nb);
    memcpy(xmat + (size_t)t * 9 * m->nbody, d->xmat, 3 * nb);
    if (collisions)
      for (int i = 0; i < d->ncon; ++i) {
        if (count >= cap) return -1;
        con_frame[count] = t;
        con_geom[2 * count] = d->contact[i].geom[0];
        con_geom[2 * count + 1] = d->contact[i].geom[1];
        con_dist[count] = d->contact[i].dist;
        ++count;
      }
  }
  return count;
}
"""

#: Contacts per frame there is room for (more in a motion: the caller's Python loop).
ROOM_PER_FRAME = 32


@functools.lru_cache(maxsize=1)
def library() -> ctypes.CDLL | None:
    """The compiled loop, or None where it cannot be built."""
    dll = mujoco_c.load("kinematics", SOURCE)
    if dll is not None:
        dll.m2r_kinematics.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p,
                                       ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int] + [ctypes.c_void_p] * 7 \
            + [ctypes.c_int] + [ctypes.c_void_p] * 3
        dll.m2r_kinematics.restype = ctypes.c_int
    return dll


def run(m: mujoco.MjModel, d: mujoco.MjData, qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray,
        collisions: bool, outputs: tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The frame loop into ``outputs`` (site_xpos, xanchor, xaxis, subtree_com, xpos, xmat, rne:
    C-contiguous float64 arrays of T frames); returns the contacts (frame (K,), geoms (K, 2),
    dist (K,)), or None without the compiled loop or with more contacts than ROOM_PER_FRAME per
    frame on average."""
    dll = library()
    if dll is None:
        return None
    T = len(qpos)
    args = [np.ascontiguousarray(a, dtype=np.float64) for a in (qpos, qvel, qacc)]
    cap = ROOM_PER_FRAME * T
    frame, geom, dist = np.empty(cap, np.int32), np.empty((cap, 2), np.int32), np.empty(cap)
    n = dll.m2r_kinematics(m._address, d._address, T, *(mujoco_c.address(a) for a in args), int(collisions),
                           *(mujoco_c.address(o) for o in outputs), cap, *(mujoco_c.address(a) for a in (frame, geom, dist)))
    if n < 0:  # more contacts than room for: the Python loop
        return None
    return frame[:n].astype(np.int64), geom[:n].astype(np.int64), dist[:n].copy()

"""Per-frame forward kinematics of a trajectory: chosen site positions, body poses, hinge anchors
and a subtree's CoM over every frame of ``qpos``, in one call.

One ``mj_kinematics`` per frame (and ``mj_comPos`` when a CoM is asked), the frame loop in C
(:mod:`~motion2robot.util.mujoco_c`; where it cannot be built, the same loop in Python, the same
numbers). Units: metres; world frame, z up; rotation matrices row-major (9,).
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from motion2robot.util import mujoco_c

SOURCE = r"""
#include <string.h>
#include <mujoco/mujoco.h>

void m2r_poses(const mjModel *m, mjData *d, int T, const double *qpos, int ns, const int *sites, double *site_xpos,
               int nb, const int *bodies, double *xpos, double *xmat, int nj, const int *joints, double *xanchor,
               int com_body, double *com) {
  for (int t = 0; t < T; ++t) {
    memcpy(d->qpos, qpos + (size_t)t * m->nq, sizeof(double) * m->nq);
    mj_kinematics(m, d);
    if (com_body >= 0) mj_comPos(m, d);
    for (int i = 0; i < ns; ++i) memcpy(site_xpos + 3 * ((size_t)t * ns + i), d->site_xpos + 3 * sites[i], 3 * sizeof(double));
    for (int i = 0; i < nb; ++i) {
      memcpy(xpos + 3 * ((size_t)t * nb + i), d->xpos + 3 * bodies[i], 3 * sizeof(double));
      memcpy(xmat + 9 * ((size_t)t * nb + i), d->xmat + 9 * bodies[i], 9 * sizeof(double));
    }
    for (int i = 0; i < nj; ++i) memcpy(xanchor + 3 * ((size_t)t * nj + i), d->xanchor + 3 * joints[i], 3 * sizeof(double));
    if (com_body >= 0) memcpy(com + 3 * (size_t)t, d->subtree_com + 3 * com_body, 3 * sizeof(double));
  }
}
"""


@dataclass(frozen=True, eq=False)
class Poses:
    """sites (T, ns, 3) positions; xpos (T, nb, 3) and xmat (T, nb, 9) body frames; anchors (T, nj, 3)
    hinge anchors; com (T, 3) the asked subtree's CoM (None when not asked)."""

    sites: np.ndarray
    xpos: np.ndarray
    xmat: np.ndarray
    anchors: np.ndarray
    com: np.ndarray | None


@functools.lru_cache(maxsize=1)
def library() -> ctypes.CDLL | None:
    """The compiled loop, or None where it cannot be built."""
    dll = mujoco_c.load("poses", SOURCE)
    if dll is not None:
        v, i = ctypes.c_void_p, ctypes.c_int
        dll.m2r_poses.argtypes = [v, v, i, v, i, v, v, i, v, v, v, i, v, v, i, v]
        dll.m2r_poses.restype = None
    return dll


def frame_poses(model: mujoco.MjModel, qpos: np.ndarray, sites: Sequence[int] = (), bodies: Sequence[int] = (),
                joints: Sequence[int] = (), com_body: int | None = None) -> Poses:
    """The poses of ``sites``, ``bodies`` and ``joints`` (ids) in every frame of ``qpos`` (T, nq),
    and the CoM of the subtree of ``com_body`` when given."""
    q = np.ascontiguousarray(qpos, dtype=np.float64).reshape(-1, model.nq)
    T = len(q)
    s, b, j = (np.ascontiguousarray(np.asarray(x, dtype=np.int32).ravel()) for x in (sites, bodies, joints))
    out = Poses(np.empty((T, len(s), 3)), np.empty((T, len(b), 3)), np.empty((T, len(b), 9)), np.empty((T, len(j), 3)),
                None if com_body is None else np.empty((T, 3)))
    d = mujoco.MjData(model)
    dll = library()
    if dll is not None:
        a = mujoco_c.address
        dll.m2r_poses(model._address, d._address, T, a(q), len(s), a(s), a(out.sites), len(b), a(b), a(out.xpos),
                      a(out.xmat), len(j), a(j), a(out.anchors), -1 if com_body is None else int(com_body), a(out.com))
        return out
    for t in range(T):
        d.qpos[:] = q[t]
        mujoco.mj_kinematics(model, d)
        if com_body is not None:
            mujoco.mj_comPos(model, d)
            out.com[t] = d.subtree_com[com_body]
        out.sites[t] = d.site_xpos[s]
        out.xpos[t] = d.xpos[b]
        out.xmat[t] = d.xmat[b]
        out.anchors[t] = d.xanchor[j]
    return out

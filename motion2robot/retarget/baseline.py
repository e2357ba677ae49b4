"""The plain formulation, for comparison: each frame solved by IPOPT in turn, warm-started from
the previous frame, with the same cost terms and weights as the fast path
(:func:`motion2robot.retarget.problem.residuals`), the temporal terms taken against the frames
already solved, the root quaternion as 4 variables with a unit-norm constraint, and the hinges
bounded by their limits and by the velocity limit from the previous frame.

Used by ``scripts/bench_retarget.py`` (speed ratio, same answer) and its test; select it with
``RetargetOptions(solver="ipopt")``.
"""

from __future__ import annotations

import functools
import time

import casadi as ca
import numpy as np

from motion2robot.retarget.compiled import CompiledProblem
from motion2robot.retarget.costs import FRAME_TERMS, Weights
from motion2robot.retarget.problem import ProblemSpec, residuals
from motion2robot.retarget.solver import SolveStats


@functools.lru_cache(maxsize=4)
def _nlp(spec: ProblemSpec) -> ca.Function:
    nq, nv = spec.robot.nq, spec.nv
    q = ca.SX.sym("q", nq)
    p = ca.SX.sym("p", spec.n_params)
    w = ca.SX.sym("w", len(FRAME_TERMS) + 2)          # frame weights, velocity, acceleration
    prev = ca.SX.sym("prev", 2 * nq)                  # q[t-1], q[t-2]
    r, _, _ = residuals(spec, q, ca.SX.zeros(nv), p, w[:len(FRAME_TERMS)])
    sv = ca.DM([1.0 / spec.length] * 3 + [1.0] * 4 + [1.0] * spec.n)
    v = sv * (q - prev[:nq])
    a = sv * (q - 2 * prev[:nq] + prev[nq:])
    f = ca.sumsqr(r) + w[len(FRAME_TERMS)] * ca.sumsqr(v) + w[len(FRAME_TERMS) + 1] * ca.sumsqr(a)
    g = ca.sumsqr(q[3:7]) - 1
    opts = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.max_iter": 100, "ipopt.tol": 1e-8,
            "ipopt.bound_relax_factor": 0.0, "calc_lam_p": False, "calc_lam_x": False}
    return ca.nlpsol("m2r_ipopt", "ipopt", {"x": q, "p": ca.vertcat(p, w, prev), "f": f, "g": g}, opts)


def solve_ipopt(problem: CompiledProblem, params: np.ndarray, q0: np.ndarray, weights: Weights,
                iterations: int, lower: np.ndarray, upper: np.ndarray, max_step: np.ndarray | None = None,
                ) -> tuple[np.ndarray, SolveStats]:
    """Frame by frame IPOPT (same signature and result as :func:`motion2robot.retarget.solver.solve`;
    ``iterations`` is unused: IPOPT runs to its tolerance). Frame 0 starts from ``q0[0]``, every
    other frame from the previous frame's solution."""
    t0 = time.perf_counter()
    spec = problem.spec
    nlp = _nlp(spec)
    T = q0.shape[0]
    wv = np.concatenate([weights.frame_vector(), [weights.velocity, weights.acceleration]])
    Q = np.zeros_like(q0)
    iters = 0
    for t in range(T):
        start = q0[0] if t == 0 else Q[t - 1]
        p1 = Q[t - 1] if t >= 1 else start
        p2 = Q[t - 2] if t >= 2 else p1
        w_t = wv.copy()
        if t == 0:
            w_t[-2:] = 0.0
        elif t == 1:
            w_t[-1] = 0.0
        lo = np.concatenate([[-np.inf] * 7, lower])
        hi = np.concatenate([[np.inf] * 7, upper])
        if max_step is not None and t >= 1:
            lo[7:] = np.maximum(lo[7:], Q[t - 1, 7:] - max_step)
            hi[7:] = np.minimum(hi[7:], Q[t - 1, 7:] + max_step)
        x0 = np.clip(start, lo, hi)
        sol = nlp(x0=x0, p=np.concatenate([params[t], w_t, p1, p2]), lbx=lo, ubx=hi, lbg=0, ubg=0)
        q = np.clip(np.asarray(sol["x"]).ravel(), lo, hi)  # IPOPT may end a hair outside its bounds
        q[3:7] /= np.linalg.norm(q[3:7])
        Q[t] = q
        iters += int(nlp.stats()["iter_count"])
    cost = np.zeros(T)
    terms = np.zeros((T, len(FRAME_TERMS)))
    return Q, SolveStats(iters, time.perf_counter() - t0, cost, terms)

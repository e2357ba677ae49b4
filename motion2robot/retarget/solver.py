"""The fast path: batched Gauss-Newton / Levenberg-Marquardt over every frame of a clip at once.

One call of the compiled, frame-mapped ``step`` function returns each frame's normal matrix
``J'J`` and gradient ``J'r`` (see :mod:`motion2robot.retarget.problem`). The temporal terms
(velocity and acceleration of the tangent-space state) couple neighbouring frames; they enter as a
block-Jacobi term (neighbours held at the current iterate), which keeps every frame's linear
system independent. Their Hessian is replaced by a diagonal that majorises it (each pair or
triple of frames gets ``|a_i| * sum|a|`` on its diagonal: 2 w_v per velocity row, 4-8-4 w_a per
acceleration row; the end frames, with fewer rows, get the interior's sum too, so that every frame
steps alike), so the simultaneous update of all frames decreases the temporal cost: with
the plain diagonal (w_v per neighbour, 1-4-1 w_a) the Jacobi iteration amplifies the odd/even
mode of a coordinate the tracking terms barely pin (iteration eigenvalue
1 - (4 w_v + 16 w_a) / (2 w_v + 6 w_a), -1.6 with the default weights), which made the output
zigzag frame to frame. A frame
whose objective went up is sent back and its damping raised (per-frame LM). Hinges are projected
onto their limits after every step, and every frame back onto its contact/floor/balance
constraints (a second-order correction, see ``solve``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from motion2robot.retarget.compiled import CompiledProblem
from motion2robot.retarget.costs import Weights
from motion2robot.retarget.problem import apply_step, tangent_diff

#: Largest change of any state coordinate in one correction step (rad, or m / leg length).
MAX_CORRECTION = 0.2
#: Squared hard-constraint residual ((m / leg length)^2) above which a frame gets the extra
#: correction steps (0.3 mm on a 0.3 m leg).
EXTRA_TOLERANCE = 1e-6
#: Damping (added to the projection's 1e-8; the Jacobian rows are m / leg length per rad) of the
#: retry after a correction step that made its frame's violation worse; x10 per further failure.
RETRY_DAMPING = 1e-4
#: Levenberg-Marquardt damping (relative to the normal matrix's diagonal) of every frame's first step.
INITIAL_DAMPING = 1e-3
#: Newton projection steps onto the hard constraints after every LM step, before it is judged
#: (a second-order correction; see ``solve``).
SECOND_ORDER = 1
#: Largest step coordinate (rad, or m / leg length) below which a frame skips that correction
#: (its drift off the constraints, ~ lever x step^2, is below 0.04 mm).
SECOND_ORDER_STEP = 0.02
#: rad the projection's bounds are widened by when hinges at a bound may move (see ``correct``).
FREE_SLACK = 1e-6


@dataclass(frozen=True)
class SolveStats:
    """Figures of one solve: iterations, seconds, final per-frame objective and per-term costs."""

    iterations: int
    time_s: float
    cost: np.ndarray     # (T,) frame objective (without temporal terms)
    terms: np.ndarray    # (T, len(FRAME_TERMS))


def _temporal(Q: np.ndarray, sv: np.ndarray, w: Weights) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Block-Jacobi gradient (T, nv), majorising diagonal (T, 1) and per-frame cost (T,) of the
    velocity and acceleration terms (state difference scaled by ``sv``: 1/L for root position, 1
    for angles); see the module docstring for the diagonal."""
    T = len(Q)
    g = np.zeros((T, len(sv)))
    diag = np.zeros((T, 1))
    cost = np.zeros(T)
    if T < 2:
        return g, diag, cost
    v = tangent_diff(Q[1:], Q[:-1]) * sv                    # v[t] = x[t+1] - x[t], (T-1, nv)
    wv, wa = w.velocity, w.acceleration
    g[1:] += wv * v * sv
    g[:-1] -= wv * v * sv
    diag[1:] += 2 * wv
    diag[:-1] += 2 * wv
    cost[1:] += wv * np.sum(v * v, axis=1)
    if T >= 3:
        a = v[1:] - v[:-1]                                  # a[t] centred at frame t+1, (T-2, nv)
        g[1:-1] += -2 * wa * a * sv
        g[:-2] += wa * a * sv
        g[2:] += wa * a * sv
        diag[1:-1] += 8 * wa
        diag[:-2] += 4 * wa
        diag[2:] += 4 * wa
        cost[1:-1] += wa * np.sum(a * a, axis=1)
    # every frame gets the interior frames' diagonal (still a majoriser): the first and last frames,
    # with fewer neighbours, would take larger steps than the rest and run ahead of them in the few
    # iterations the solver makes, leaving a transient at the clip's ends that grows with the rate
    # (op3 bow at 100 fps: the last 3 frames' root 2 m/s^2, a walk-back's shoulder at the start)
    diag[:] = diag.max()
    return g, diag, cost


def solve(problem: CompiledProblem, params: np.ndarray, q0: np.ndarray, weights: Weights,
          iterations: int, lower: np.ndarray, upper: np.ndarray, max_step: np.ndarray | None = None,
          tol: float = 1e-12, second_order: int | None = None) -> tuple[np.ndarray, SolveStats]:
    """Minimise every frame's objective from ``q0`` (T, nq) with frame parameters ``params``
    (T, n_params); returns the (T, nq) solution and its figures. Hinges stay within [lower, upper].

    max_step: (n,) largest hinge change between frames (rad; velocity limit / fps). When given,
    each frame's hinges are also bounded to within ``max_step`` of both neighbours' current values
    (start from a trajectory that satisfies it; finish with an exact clamping pass).

    Per-frame LM: a frame whose objective (its own terms + the temporal terms with its neighbours)
    went up is put back and retried with ten times the damping (its new step is computed in the
    next round, which costs the frame a round but keeps one step evaluation per round).

    second_order: Newton projections onto the contact, floor and balance rows (``settle``) after
    every step, before the step is judged (default :data:`SECOND_ORDER`; frames whose step is
    below :data:`SECOND_ORDER_STEP` skip it). The hard terms are stiff penalties (weights 1e5):
    a step along the curved constraint surface leaves it to second order (0.3 mm for 0.06 rad on
    a 10 cm lever), the penalty charges that more than the step gained, the step is refused and
    the damping climbs, so plain LM crawls along the constraints (the Maratos effect). With the
    correction the same steps are taken: on the pinned stage of the bench's 40-frame probe 10
    iterations come within 1.3 % of IPOPT's objective and 50 below it (without: 44 % and 20 % above)."""
    t0 = time.perf_counter()
    spec = problem.spec
    T, nv = q0.shape[0], spec.nv
    sv2 = np.ones(nv)
    sv2[:3] = 1.0 / spec.length ** 2
    sv = np.sqrt(sv2)
    step = problem.step_eval(T)
    wvec = np.array(weights.frame_vector())
    Q = q0.copy()
    Q[:, 7:] = np.clip(Q[:, 7:], lower, upper)
    lam = np.full(T, INITIAL_DAMPING)
    second_order = SECOND_ORDER if second_order is None else second_order
    n = nv - 6
    lm = np.zeros((T, 1 + 2 * nv + 2 * n))
    f_prev = np.full(T, np.inf)
    Q_prev = Q.copy()
    retried = np.zeros(T, dtype=bool)  # frames put back in the round before
    it = 0
    for it in range(1, iterations + 1):
        gt, dt, ct = _temporal(Q, sv, weights)
        lm[:, 0] = lam
        lm[:, 1:1 + nv] = dt * sv2 + weights.damping
        lm[:, 1 + nv:1 + 2 * nv] = gt
        lo, hi = hinge_bounds(Q[:, 7:], lower, upper, max_step)
        lm[:, 1 + 2 * nv:1 + 2 * nv + n] = lo
        lm[:, 1 + 2 * nv + n:] = hi
        dx, cost, _ = step(Q, params, wvec, lm)
        f = cost[:, 0] + ct
        # a frame put back in the round before sits where it was judged: its objective moved only
        # with its neighbours, so it is not judged again (else it could be put back for ever)
        bad = (f > f_prev * (1 + 1e-12)) & ~retried
        if bad.any():  # put those frames back; their step is recomputed next round with more damping
            Q[bad] = Q_prev[bad]
            f[bad] = f_prev[bad]
            dx[bad] = 0.0
        # a frame put back in the round before has not moved since: its zero gain is no success
        # (its damping stays) and says nothing about convergence
        lam = np.where(bad, lam * 10.0, np.where(retried, lam, np.maximum(lam * 0.3, 1e-7)))
        if not bad.any() and not retried.any() and np.max(f_prev - f) < tol:
            break
        retried = bad
        f_prev, Q_prev = f, Q.copy()
        Q = apply_step(Q, dx)
        Q[:, 7:] = np.clip(Q[:, 7:], lo, hi)
        rows = np.flatnonzero(np.abs(dx).max(axis=1) > SECOND_ORDER_STEP) if second_order else ()
        if len(rows):  # back onto the hard constraints before the step is judged
            box = _projection_settings(np.zeros(len(rows)), lo[rows], hi[rows], nv)
            for _ in range(second_order):
                Q[rows] = apply_step(Q[rows], problem.settle_eval(len(rows))(Q[rows], params[rows], box)[0])
                Q[rows, 7:] = np.clip(Q[rows, 7:], lo[rows], hi[rows])
    cost, terms = problem.cost_eval(T)(Q, params, wvec)
    bad = cost[:, 0] + _temporal(Q, sv, weights)[2] > f_prev * (1 + 1e-12)
    if bad.any():  # the last step made these frames worse: keep their previous iterate
        Q[bad] = Q_prev[bad]
        cost[bad], terms[bad] = problem.cost_eval(int(bad.sum()))(Q[bad], params[bad], wvec)
    return Q, SolveStats(it, time.perf_counter() - t0, cost[:, 0], terms)


def hinge_bounds(q: np.ndarray, lower: np.ndarray, upper: np.ndarray, max_step: np.ndarray | None,
                 rows: np.ndarray | None = None):
    """Per-frame hinge bounds (T, n): the joint limits (``lower``/``upper`` (n,) or (T, n)),
    tightened to ``max_step`` of the neighbours' current values (never excluding the current
    value); with ``rows``, those frames' only (len(rows), n), the same numbers."""
    if rows is None:
        rows = np.arange(len(q))
    qr = q[rows]
    lo = (lower[rows] if np.ndim(lower) == 2 else np.broadcast_to(lower, qr.shape)).copy()
    hi = (upper[rows] if np.ndim(upper) == 2 else np.broadcast_to(upper, qr.shape)).copy()
    if max_step is not None and len(q) > 1:
        prev, nxt = rows >= 1, rows < len(q) - 1
        lo[prev] = np.maximum(lo[prev], q[rows[prev] - 1] - max_step)
        lo[nxt] = np.maximum(lo[nxt], q[rows[nxt] + 1] - max_step)
        hi[prev] = np.minimum(hi[prev], q[rows[prev] - 1] + max_step)
        hi[nxt] = np.minimum(hi[nxt], q[rows[nxt] + 1] + max_step)
        lo, hi = np.minimum(lo, qr), np.maximum(hi, qr)
    return lo, hi


def _projection_settings(damping: np.ndarray, lo: np.ndarray, hi: np.ndarray, nv: int) -> np.ndarray:
    """The ``lm`` input (frames, 1 + 2 nv + 2 n) of ``project``/``settle``: extra damping (frames,)
    and the hinge box ``lo``, ``hi`` (frames, n); the step's temporal slots stay zero."""
    n = lo.shape[1]
    lm = np.zeros((len(lo), 1 + 2 * nv + 2 * n))
    lm[:, 0] = damping
    lm[:, 1 + 2 * nv:1 + 2 * nv + n] = lo
    lm[:, 1 + 2 * nv + n:] = hi
    return lm


def correct(problem: CompiledProblem, params: np.ndarray, Q: np.ndarray, lower: np.ndarray, upper: np.ndarray,
            max_step: np.ndarray | None, iterations: int, free_at_bounds: bool = False,
            extra: int = 0, collisions: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Newton projection onto the hard constraints (see ``project`` in
    :mod:`motion2robot.retarget.problem`), hinges within ``lower``/``upper`` ((n,), or (T, n) per
    frame: equal bounds hold a hinge), ``iterations`` times over every frame, then up to
    ``extra`` more times over the frames still violating them (squared residual above
    :data:`EXTRA_TOLERANCE`; deep self-collisions need ~10 steps); hinges stay in their per-frame
    bounds. Returns the corrected (T, nq) qpos and each frame's remaining squared violation.

    A step that made its frame's violation worse (a far linearisation, or rows that cannot all be
    zeroed, whose nearly singular system gives a huge step in a useless direction) is undone and
    replaced by a damped step from there (Levenberg-Marquardt on the projection: damping
    :data:`RETRY_DAMPING`, x10 per further failure, /10 per success).

    free_at_bounds: hinges at a bound take part in the step too (the projection holds them
    otherwise), the step being clipped into the bounds afterwards; for frames stuck with every
    useful hinge at a velocity bound. collisions False: the rows without self-collision (``settle``),
    and the violation returned is theirs."""
    T, nv = Q.shape[0], problem.spec.nv
    project = problem.project_eval if collisions else problem.settle_eval
    slack = FREE_SLACK if free_at_bounds else 0.0
    Q = Q.copy()
    Q_prev, v_prev = Q.copy(), np.full(T, np.inf)
    mu = np.zeros(T)  # per-frame extra damping of the projection step

    def settings(damping: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """The projection's ``lm`` input of some frames: their damping, their hinge box."""
        return _projection_settings(damping, lo - slack, hi + slack, nv)

    for k in range(iterations + extra):
        rows = np.arange(T) if k < iterations else np.flatnonzero(v_prev > EXTRA_TOLERANCE)
        if not len(rows):
            break
        lo, hi = hinge_bounds(Q[:, 7:], lower, upper, max_step, rows)  # the frames stepped only
        dx, v = project(len(rows))(Q[rows], params[rows], settings(mu[rows], lo, hi))
        v = v[:, 0]
        worse = v > v_prev[rows]
        mu[rows] = np.where(worse, np.maximum(mu[rows] * 10.0, RETRY_DAMPING), mu[rows] * 0.1)
        if worse.any():  # back to the previous iterate, a damped step from there
            back = rows[worse]
            Q[back], v[worse] = Q_prev[back], v_prev[back]
            lo, hi = hinge_bounds(Q[:, 7:], lower, upper, max_step, rows)
            dx[worse] = project(len(back))(Q[back], params[back], settings(mu[back], lo[worse], hi[worse]))[0]
        dx *= np.minimum(1.0, MAX_CORRECTION / np.maximum(np.abs(dx).max(axis=1), 1e-12))[:, None]
        Q_prev[rows], v_prev[rows] = Q[rows], v
        Q[rows] = apply_step(Q[rows], dx)
        Q[rows, 7:] = np.clip(Q[rows, 7:], lo, hi)
    # the last steps' outcome: a frame made worse goes back
    if collisions:
        v = problem.violation_eval(T)(Q, params)[0][:, 0]
    else:
        v = project(T)(Q, params, _projection_settings(np.zeros(T), Q[:, 7:], Q[:, 7:], nv))[1][:, 0]
    worse = v > v_prev
    Q[worse], v[worse] = Q_prev[worse], v_prev[worse]
    return Q, v


def objective(problem: CompiledProblem, params: np.ndarray, Q: np.ndarray, weights: Weights) -> tuple[np.ndarray, np.ndarray]:
    """The objective of trajectory ``Q`` (T, nq): per-frame per-term costs (T, len(FRAME_TERMS))
    and per-frame temporal cost (T,) (velocity + acceleration of the tangent-space state)."""
    T, nv = Q.shape[0], problem.spec.nv
    sv = np.ones(nv)
    sv[:3] = 1.0 / problem.spec.length
    _, terms = problem.cost_eval(T)(Q, params, np.array(weights.frame_vector()))
    return terms, _temporal(Q, sv, weights)[2]


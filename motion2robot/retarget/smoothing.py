"""Smooth hinge trajectories whose speed or acceleration exceed the servo's limits.

Per joint, the trajectory ``q`` (rad) closest to the solver's ``r`` in the sense of

    sum_t (q_t - r_t)^2 + sum_t u_t (q_{t+1} - q_t)^2 + sum_t m_t (q_{t+1} - 2 q_t + q_{t-1})^2

is a pentadiagonal linear solve. The weights start at zero and are raised, by iteratively
reweighted least squares, only on the rows (frames) whose speed or acceleration is over its
target, so the motion keeps its shape where it is within the limits and is rounded off (not
clipped into a bang-bang) where it is not. An exact velocity clamp and the joint-limit clip
follow (see :mod:`~motion2robot.retarget.constraints`); after smoothing they move little.

The targets come from the robot model (:func:`servo_targets`): the speed limit, and the torque
budget of a servo that must also drive its own rotor inertia (armature * acceleration) and
friction (damping * speed), as the validator's torque check counts them. For quasi-static motions
the root position is smoothed too (:func:`root_acceleration_target`): its acceleration moves the
ZMP. The retargeter alternates this smoothing with the exact correction onto the hard
constraints (:func:`~motion2robot.retarget.solver.correct`), which moves the legs little.
"""

from __future__ import annotations

import numpy as np

from motion2robot.retarget import native
from motion2robot.retarget.constraints import clamp_velocity

#: Fraction of the velocity / acceleration limit aimed at (headroom for the later corrections).
SPEED_TARGET = 0.95
ACCELERATION_TARGET = 0.8
#: Shares of the servo torque given to its own damping (speed) and rotor inertia (acceleration)
#: when the model declares them; the rest is left for gravity and the links' inertia.
DAMPING_SHARE = 0.55
ARMATURE_SHARE = 0.3
#: m the ZMP may move away from the CoM ground projection by the root's acceleration alone
#: (quasi-static motions: the root acceleration target is g * ZMP_SHIFT / root height).
ZMP_SHIFT = 0.01
GRAVITY = 9.81
#: Reweighting passes of :func:`smooth_jointly`: one weight per frame for every column converges
#: more slowly than per column (at 100 fps, 16 passes left a stance's root 30 % over its target).
JOINT_ITERATIONS = 40
#: rad/s^2, acceleration limit of joints whose model declares no armature (as the validator).
DEFAULT_ACCELERATION = 100.0
#: Hz, cutoff of :func:`low_pass`: above the content of human motion, below what per-frame solves
#: add as noise (whose accelerations grow with the square of the frame rate).
CUTOFF_HZ = 8.0


def servo_targets(robot) -> tuple[np.ndarray, np.ndarray]:
    """(n,) speed (rad/s) and (n,) acceleration (rad/s^2) the smoothing aims at: a fraction of the
    speed limit and of torque limit / armature (the reflected rotor inertia alone caps it, as the
    validator's ``acceleration`` check), lowered so that damping * speed and armature *
    acceleration together stay within the torque limit where the model declares them."""
    m = robot.model
    dof = m.jnt_dofadr[np.asarray(robot.joint_ids)]
    arm, damp = m.dof_armature[dof], m.dof_damping[dof]
    tau = np.asarray(robot.torque_limit, dtype=float)
    amax = np.where(arm > 0, tau / np.where(arm > 0, arm, 1.0), DEFAULT_ACCELERATION)
    v = SPEED_TARGET * np.asarray(robot.velocity_limit, dtype=float)
    v = np.where(damp > 0, np.minimum(v, DAMPING_SHARE * tau / np.where(damp > 0, damp, 1.0)), v)
    a = np.where(damp > 0, min(ACCELERATION_TARGET, ARMATURE_SHARE), ACCELERATION_TARGET) * amax
    return v, a


def root_acceleration_target(robot) -> float:
    """m/s^2 of root acceleration that moves the ZMP by about ZMP_SHIFT (linear inverted
    pendulum at the nominal root height)."""
    return GRAVITY * ZMP_SHIFT / float(robot.nominal_qpos[2])


def pentadiagonal_solve(d0: np.ndarray, d1: np.ndarray, d2: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve ``A x = b`` for symmetric positive definite pentadiagonal matrices, one per column:
    d0 (T, k) diagonal, d1 (T-1, k) first and d2 (T-2, k) second super-diagonal, b (T, k).
    Runs the compiled kernel of :mod:`~motion2robot.retarget.native` when there is one."""
    fast = native.penta_solve(d0, d1, d2, b)
    if fast is not None:
        return fast
    T = len(d0)
    l0 = np.empty_like(d0)
    l1 = np.zeros_like(d0)   # l1[t] = L[t, t-1]
    l2 = np.zeros_like(d0)   # l2[t] = L[t, t-2]
    y = np.empty_like(b)
    for t in range(T):
        s = d0[t].copy()
        r = b[t].copy()
        if t >= 2:
            l2[t] = d2[t - 2] / l0[t - 2]
            s -= l2[t] * l2[t]
            r -= l2[t] * y[t - 2]
        if t >= 1:
            l1[t] = (d1[t - 1] - l2[t] * l1[t - 1]) / l0[t - 1] if t >= 2 else d1[t - 1] / l0[t - 1]
            s -= l1[t] * l1[t]
            r -= l1[t] * y[t - 1]
        l0[t] = np.sqrt(s)
        y[t] = r / l0[t]
    x = np.empty_like(b)
    for t in range(T - 1, -1, -1):
        r = y[t].copy()
        if t + 1 < T:
            r -= l1[t + 1] * x[t + 1]
        if t + 2 < T:
            r -= l2[t + 2] * x[t + 2]
        x[t] = r / l0[t]
    return x


def _smooth(r: np.ndarray, u: np.ndarray, m: np.ndarray, w: np.ndarray | None = None) -> np.ndarray:
    """Minimiser of the weighted objective of the module docstring; u (T-1, k), m (T-2, k); ``w``
    (T, k) weights of the first sum (None: all 1)."""
    T = len(r)
    d0 = np.ones_like(r) if w is None else np.array(w, dtype=np.float64)
    r = r if w is None else w * r
    d1 = np.zeros((T - 1, r.shape[1]))
    d2 = np.zeros((max(T - 2, 0), r.shape[1]))
    d0[:-1] += u
    d0[1:] += u
    d1 -= u
    if T >= 3:
        d0[:-2] += m
        d0[1:-1] += 4 * m
        d0[2:] += m
        d1[:-1] -= 2 * m
        d1[1:] -= 2 * m
        d2 += m
    return pentadiagonal_solve(d0, d1, d2, r)


def _steps(shape: tuple[int, ...], vtarget, atarget, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """Per-frame speed and acceleration targets ((k,) per frame and per frame squared)."""
    return (np.broadcast_to(np.asarray(vtarget, dtype=float) / fps, shape),
            np.broadcast_to(np.asarray(atarget, dtype=float) / fps ** 2, shape))


def _irls(r: np.ndarray, vstep: np.ndarray, astep: np.ndarray, iterations: int, shared: bool) -> np.ndarray:
    """Iteratively reweighted smoothing of ``r`` (T, k): the weights of rows over their targets
    grow until none is (or ``iterations`` ran out); ``shared``: one weight per row for all columns."""
    T, k = r.shape
    cols = 1 if shared else k
    u, m = np.zeros((T - 1, cols)), np.zeros((T - 2, cols))
    y = r
    for _ in range(iterations):
        rv = np.abs(np.diff(y, axis=0)) / vstep
        ra = np.abs(np.diff(y, 2, axis=0)) / astep
        if shared:
            rv, ra = rv.max(axis=1, keepdims=True), ra.max(axis=1, keepdims=True)
        if rv.max() <= 1.0 and ra.max() <= 1.0:
            break
        u = np.where(rv > 1.0, (u + 1.0) * rv * rv, u)
        m = np.where(ra > 1.0, (m + 1.0) * ra * ra, m)
        y = _smooth(r, np.broadcast_to(u, (T - 1, k)), np.broadcast_to(m, (T - 2, k)))
    return y


def smooth_to_targets(x: np.ndarray, vtarget: np.ndarray, atarget: np.ndarray, fps: float,
                      iterations: int = 16) -> np.ndarray:
    """(T, k) trajectories near ``x`` with speed <= ``vtarget`` and acceleration <= ``atarget``
    ((k,) per second and per second squared, in x's unit; inf = no target) where the reweighting
    reached them. Columns already within both targets are returned unchanged."""
    out = np.array(x, dtype=np.float64)
    if len(out) < 3:
        return out
    vstep, astep = _steps(out.shape[1:], vtarget, atarget, fps)
    cols = np.flatnonzero((np.abs(np.diff(out, axis=0)) > vstep).any(axis=0)
                          | (np.abs(np.diff(out, 2, axis=0)) > astep).any(axis=0))
    if len(cols):
        r = out[:, cols]
        fast = native.smooth_irls(r, vstep[cols], astep[cols], iterations)
        out[:, cols] = fast if fast is not None else _irls(r, vstep[cols], astep[cols], iterations, shared=False)
    return out


def smooth_hinges(q: np.ndarray, vtarget: np.ndarray, atarget: np.ndarray, fps: float, vmax: np.ndarray,
                  lower: np.ndarray, upper: np.ndarray, iterations: int = 16) -> np.ndarray:
    """(T, n) hinge angles (rad) near ``q`` with speed <= ``vtarget`` (rad/s) and acceleration
    <= ``atarget`` (rad/s^2) where the reweighting reached them (see :func:`servo_targets` and
    :func:`smooth_to_targets`); then exactly within the speed limit ``vmax`` and [lower, upper]."""
    out = smooth_to_targets(q, vtarget, atarget, fps, iterations)
    return np.clip(clamp_velocity(out, vmax, fps), lower, upper)


def smooth_jointly(x: np.ndarray, vtarget: np.ndarray, atarget: np.ndarray, fps: float,
                   iterations: int = JOINT_ITERATIONS) -> np.ndarray:
    """(T, k) trajectories near ``x`` with ONE smoothing filter for every column: the rows
    (frames) whose speed or acceleration is over its target in any column get the same weights in
    all columns. Applied to a whole configuration (root and hinges together), the filtered path is
    a time average of nearby configurations, so a point pinned by the kinematics (a planted sole)
    moves only to second order in the smoothed-away deviation: single-frame kinks the per-frame
    solves leave are removed without the projection that would put them back."""
    out = np.array(x, dtype=np.float64)
    if len(out) < 3:
        return out
    vstep, astep = _steps(out.shape[1:], vtarget, atarget, fps)
    return _irls(out, vstep, astep, iterations, shared=True)


def low_pass(x: np.ndarray, fps: float, cutoff_hz: float = CUTOFF_HZ, lower: np.ndarray | None = None,
             upper: np.ndarray | None = None) -> np.ndarray:
    """(T, k) trajectories with content above ``cutoff_hz`` removed, the same filter at any frame
    rate: the minimiser of ``sum (y - x)^2 + m sum (second difference of y)^2`` with
    ``m = (fps / (2 pi cutoff_hz))^4`` (gain 1 / (1 + (f / cutoff)^4) at frequencies f well below
    the Nyquist rate), one weight
    for every column (a whole configuration filtered at once: pinned points move to second order).
    At 20-30 fps it barely acts; at 100 fps it removes the solver noise a finer rate reveals.

    ``lower``/``upper`` (k,) (None or +-inf: unbounded): the same minimiser within the bounds
    (:func:`_bounded`), so a trajectory resting at a bound is not rounded past it and then clipped
    (a kink: its acceleration grows with the frame rate)."""
    out = np.array(x, dtype=np.float64)
    T = len(out)
    if T < 3:
        return out
    m = np.full((T - 2, out.shape[1]), (fps / (2.0 * np.pi * cutoff_hz)) ** 4)
    u = np.zeros((T - 1, out.shape[1]))
    if lower is None and upper is None:
        return _smooth(out, u, m)
    return _bounded(out, u, m, lower, upper)


#: Weight (relative to the data term's 1) that holds a frame at the bound it would cross, and the
#: active-set passes of :func:`_bounded` at most.
BOUND_WEIGHT = 1e8
BOUND_ITERATIONS = 30


def _bounded(x: np.ndarray, u: np.ndarray, m: np.ndarray, lower: np.ndarray | None,
             upper: np.ndarray | None) -> np.ndarray:
    """Minimiser of the objective of :func:`_smooth` (data weight 1) subject to lower <= y <= upper
    per column, by a primal-dual active set: frames past a bound are held at it (weight
    BOUND_WEIGHT), held frames the rest of the objective pulls back inside are released, until the
    set stops changing; the last residue (~1/BOUND_WEIGHT) is clipped. It meets the bound without
    a kink: its peak acceleration does not grow with the frame rate, as a clip after the filter's
    does (see tests/test_retarget_smoothing.py)."""
    T, k = x.shape
    lo = np.broadcast_to(-np.inf if lower is None else np.asarray(lower, dtype=np.float64), (k,))
    hi = np.broadcast_to(np.inf if upper is None else np.asarray(upper, dtype=np.float64), (k,))
    y = _smooth(x, u, m)
    at_lo = np.zeros((T, k), dtype=bool)
    at_hi = np.zeros((T, k), dtype=bool)
    for _ in range(BOUND_ITERATIONS):
        # a held frame stays held while the rest of the objective pushes it outwards (its residue
        # is on the far side of the bound); a free frame past a bound is taken
        new_lo = np.where(at_lo, y <= lo, y < lo)
        new_hi = np.where(at_hi, y >= hi, y > hi)
        cols = np.flatnonzero((new_lo != at_lo).any(axis=0) | (new_hi != at_hi).any(axis=0))
        if not len(cols):
            break
        at_lo, at_hi = new_lo, new_hi
        held = (at_lo | at_hi)[:, cols]     # the columns are independent: only these change
        w = np.where(held, 1.0 + BOUND_WEIGHT, 1.0)
        goal = np.where(at_lo[:, cols], lo[cols], np.where(at_hi[:, cols], hi[cols], 0.0))
        y[:, cols] = _smooth((x[:, cols] + BOUND_WEIGHT * goal * held) / w, u[:, cols], m[:, cols], w)
    return np.clip(y, lo, hi)


def spread_correction(before: np.ndarray, after: np.ndarray, joints: np.ndarray, fps: float,
                      half_width: float = 0.2) -> np.ndarray:
    """``after`` (T, n) hinge angles with the correction ``after - before`` of the ``joints`` (n,)
    bool spread in time: each frame's correction becomes a raised-cosine bump of ``half_width``
    seconds, and every joint takes, per sign, the largest bump over the frames near it. Every
    frame keeps at least its own correction (same sign, same or larger size), so a limb pushed out
    of the body stays out, but a push confined to one frame no longer makes a one-frame spike
    (the projections onto self-collision do exactly that). Meant for joints that no equality
    constraint holds (arms, head), where a larger push in the same direction is still feasible."""
    out = np.array(after, dtype=np.float64)
    if not np.any(joints) or len(out) < 3:
        return out
    w = max(1, int(round(half_width * fps)))
    offsets = np.arange(-w, w + 1)
    bump = 0.5 + 0.5 * np.cos(np.pi * offsets / (w + 1))            # (2w+1,), 1 at the centre
    d = (after - before)[:, joints]
    T = len(d)
    pos = np.zeros_like(d)
    neg = np.zeros_like(d)
    for k, b in zip(offsets, bump):  # envelope(s) = max_t d(t) bump(s - t)
        src = np.clip(np.arange(T) - k, 0, T - 1)
        valid = ((np.arange(T) - k) >= 0) & ((np.arange(T) - k) < T)
        shifted = np.where(valid[:, None], d[src], 0.0) * b
        pos = np.maximum(pos, shifted)
        neg = np.minimum(neg, shifted)
    out[:, joints] = before[:, joints] + pos + neg
    return out

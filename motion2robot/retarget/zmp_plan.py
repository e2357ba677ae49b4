"""Dynamic balance: a CoM path whose ZMP stays inside the support polygons, for the IK to track.

The whole-body solve keeps the CoM over the (shrunk) support polygon: static balance. Once
anything accelerates, the ZMP moves away from the CoM. This stage measures the multi-body ZMP of
the solved trajectory (the validator's inverse dynamics, so arms and legs count) and corrects the
CoM path with the cart-table model (a linear inverted pendulum at the CoM's height z_c): moving
the CoM by d(t) moves the ZMP by

    d(t) - (z_c / g) d''(t),

linear in d. One QP over the whole clip (casadi's OSQP) finds the smallest, smoothest d that puts
the corrected ZMP inside every supported frame's shrunk polygon (per-frame half-planes from the
contact schedule), with a slack charged heavily where no such d exists; d starts and ends at rest.
The retargeter then pins the CoM within ``TRACK_TOLERANCE`` of c + d as a hard constraint (the
balance rows, boxes instead of polygons) and projects the trajectory onto it; two rounds absorb
what the pendulum model misses.

Units: metres, seconds; world frame, z up.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from motion2robot.retarget.problem import HMAX

GRAVITY = 9.81
#: m, half-width of the box the CoM is pinned to around its planned position.
TRACK_TOLERANCE = 0.002
#: s, time scale of the smoothness terms (velocity x tau, acceleration x tau^2 weigh like a shift).
SMOOTH_TIME = 0.15
#: Cost of a metre of ZMP outside the polygon relative to a metre of CoM shift (linear + quadratic).
SLACK_COST = 1e3
#: m; a correction below this everywhere is not applied.
MIN_SHIFT = 5e-4


def multibody_zmp(qpos: np.ndarray, fps: float, robot) -> tuple[np.ndarray, np.ndarray]:
    """(zmp (T, 2) with NaN where the robot is not pushed down, com (T, 3)) of a trajectory, by
    the validator's inverse dynamics (finite differences of ``qpos``; no collision pass: the ZMP
    does not read contacts)."""
    from motion2robot.robot_motion import RobotMotion
    from motion2robot.validate.dynamics import root_wrench, zmp_of_wrench
    from motion2robot.validate.kinematics import compute_kinematics

    kin = compute_kinematics(RobotMotion(qpos, fps, robot.joint_names, robot.name), robot, collisions=False)
    zmp = zmp_of_wrench(kin.qpos[:, :3], root_wrench(kin), 0.05 * robot.mass * GRAVITY)
    return zmp, kin.com


@functools.lru_cache(maxsize=1)
def _osqp_options() -> dict:
    return {"osqp": {"verbose": False, "eps_abs": 1e-7, "eps_rel": 1e-7, "max_iter": 20000, "polish": True},
            "error_on_fail": False}


def _sparse(rows, cols, vals, n: int, m: int) -> ca.DM:
    """A sparse (n, m) casadi matrix from triplets, duplicates summed (casadi keeps only one)."""
    key = np.asarray(rows, dtype=np.int64) * m + np.asarray(cols, dtype=np.int64)
    uniq, inv = np.unique(key, return_inverse=True)
    total = np.zeros(len(uniq))
    np.add.at(total, inv, np.asarray(vals, dtype=float))
    return ca.DM.triplet((uniq // m).tolist(), (uniq % m).tolist(), ca.DM(total.tolist()), n, m)


def _second_difference(T: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triplets of D2 (T x T) with replicated ends (zero velocity outside the clip):
    (D2 d)_t = d_{t+1} - 2 d_t + d_{t-1}."""
    t = np.arange(T)
    rows = np.concatenate([t, t, t])
    cols = np.concatenate([np.maximum(t - 1, 0), t, np.minimum(t + 1, T - 1)])
    vals = np.concatenate([np.ones(T), -2.0 * np.ones(T), np.ones(T)])
    return rows, cols, vals


@functools.lru_cache(maxsize=16)
def _hessian(T: int, fps: float, jerk_time: float) -> ca.DM:
    """The QP's cost matrix over (d_x, d_y, slack) (3T, 3T): the smoothness I + tau^2 D1'D1 +
    tau^4 D2'D2 (+ jerk_time^6 D3'D3) on each axis, SLACK_COST on the slack; the same for every
    clip of T frames at ``fps`` (cached; never modified)."""
    r2, c2, v2 = _second_difference(T)
    t = np.arange(T - 1)
    D1 = _sparse(np.r_[t, t], np.r_[t, t + 1], np.r_[-np.ones(T - 1), np.ones(T - 1)] * fps, T - 1, T)
    D2 = _sparse(r2, c2, v2 * fps ** 2, T, T)
    tau = SMOOTH_TIME
    Hd = ca.DM.eye(T) + tau ** 2 * ca.mtimes(D1.T, D1) + tau ** 4 * ca.mtimes(D2.T, D2)
    if jerk_time > 0.0:
        D3 = ca.mtimes(D1, D2)
        Hd = Hd + jerk_time ** 6 * ca.mtimes(D3.T, D3)
    return ca.diagcat(Hd, Hd, SLACK_COST * ca.DM.eye(T))


def cart_table_shift(zmp: np.ndarray, com_z: np.ndarray, planes: np.ndarray, support: np.ndarray,
                     fps: float, jerk_time: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """CoM shift d (T, 2) putting the cart-table-corrected ZMP inside ``planes`` (T, HMAX, 3) rows
    n . p <= b in the ``support`` (T,) frames, and the ZMP's remaining distance outside (T,) (m).

    zmp (T, 2): the trajectory's ZMP (NaN rows are left unconstrained); com_z (T,) CoM heights;
    jerk_time: s, weight of the shift's jerk (jerk x jerk_time^3 weighs like a shift; 0 = not
    charged): with it the CoM's acceleration, and so the ZMP, changes smoothly where the support
    polygon changes instead of jumping in one frame. A ZMP that already meets every constraint as
    it is (every row's room >= 0) gets no shift without solving the QP: its optimum is then
    exactly none."""
    T = len(zmp)
    frames, fi, n_x, n_y, rhs = _constraints(zmp, planes, support)
    k = len(fi)
    if T < 3 or not k or np.all(rhs >= 0.0):
        return np.zeros((T, 2)), np.zeros(T)
    # M = I - (z_c / g) fps^2 D2: the ZMP change per axis is M d; row t holds (t, 1) then its three
    # D2 entries (t-1, t, t+1, ends replicated), in this order
    a = -(com_z[frames] / GRAVITY) * fps ** 2
    m_col = np.stack([frames, np.maximum(frames - 1, 0), frames, np.minimum(frames + 1, T - 1)], axis=1)
    m_val = np.stack([np.ones(len(frames)), a * 1.0, a * -2.0, a * 1.0], axis=1)
    kk = np.arange(k)
    c, v = m_col[fi], m_val[fi]  # (k, 4)
    # per constraint: (x column, y column) for each of the 4 entries, then its slack
    rr = np.concatenate([np.repeat(kk, 8).reshape(k, 8), kk[:, None]], axis=1).ravel()
    cc = np.concatenate([np.stack([c, T + c], axis=2).reshape(k, 8), (2 * T + frames[fi])[:, None]], axis=1).ravel()
    vv = np.concatenate([np.stack([n_x[:, None] * v, n_y[:, None] * v], axis=2).reshape(k, 8),
                         np.full((k, 1), -1.0)], axis=1).ravel()
    A = _sparse(rr, cc, vv, k, 3 * T)
    H = _hessian(T, float(fps), float(jerk_time))
    g = np.concatenate([np.zeros(2 * T), np.full(T, SLACK_COST * 1e-2)])
    solver = ca.conic("zmp_plan", "osqp", {"h": H.sparsity(), "a": A.sparsity()}, _osqp_options())
    lbx = np.concatenate([np.full(2 * T, -np.inf), np.zeros(T)])
    res = solver(h=H, g=g, a=A, lba=-np.inf, uba=np.asarray(rhs), lbx=lbx, ubx=np.inf)
    x = np.asarray(res["x"]).ravel()
    if not np.all(np.isfinite(x)):
        return np.zeros((T, 2)), np.zeros(T)
    return np.stack([x[:T], x[T:2 * T]], axis=1), np.maximum(x[2 * T:], 0.0)


def _constraints(zmp: np.ndarray, planes: np.ndarray,
                 support: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The rows of :func:`cart_table_shift`'s constraints: the constrained frames (F,) (``support``
    with a finite ZMP), then per (frame, plane) row, frame-major, the index into those frames (k,),
    the plane's normal (k,) x and y, and its room b - n . zmp (k,) (``planes`` (T, HMAX, 3) rows
    n . p <= b; all-zero normals are padding)."""
    frames = np.flatnonzero(support & np.isfinite(zmp).all(axis=1))
    pl = planes[frames]
    fi, hi = np.nonzero(~((pl[..., 0] == 0.0) & (pl[..., 1] == 0.0)))
    n_x, n_y, b = pl[fi, hi, 0], pl[fi, hi, 1], pl[fi, hi, 2]
    return frames, fi, n_x, n_y, b - n_x * zmp[frames[fi], 0] - n_y * zmp[frames[fi], 1]


def com_boxes(target: np.ndarray, frames: np.ndarray, planes: np.ndarray, tol: float = TRACK_TOLERANCE) -> np.ndarray:
    """``planes`` (T, HMAX, 3) with the ``frames`` (T,) bool replaced by the box |c - target| <= tol."""
    out = planes.copy()
    box = np.tile([0.0, 0.0, 1.0], (len(target), HMAX, 1))
    box[:, 0] = np.stack([np.ones(len(target)), np.zeros(len(target)), target[:, 0] + tol], axis=1)
    box[:, 1] = np.stack([-np.ones(len(target)), np.zeros(len(target)), -target[:, 0] + tol], axis=1)
    box[:, 2] = np.stack([np.zeros(len(target)), np.ones(len(target)), target[:, 1] + tol], axis=1)
    box[:, 3] = np.stack([np.zeros(len(target)), -np.ones(len(target)), -target[:, 1] + tol], axis=1)
    out[frames] = box[frames]
    return out

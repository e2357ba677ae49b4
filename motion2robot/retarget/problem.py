"""The per-frame retargeting problem as casadi functions, built from a :class:`Robot`.

Decision variables per frame: ``qpos`` (root xyz, root wxyz, n hinges). Steps are taken in the
tangent space ``dx = (dp (3), dtheta (3, root-local rotation vector), dq (n))`` so the quaternion
stays unit: see :func:`apply_step`.

Six functions are built (SX, so they can be mapped and code-generated). Points enter to first
order in the step (:class:`~motion2robot.robot.kinematics.TangentFrames`): exact value and
Jacobian at ``dx = 0``, the Jacobian by joint axis x lever arm instead of differentiating the chain.

- ``step(qpos, p, w, lm) -> (dx, cost, terms)``: the Levenberg-Marquardt step
  ``dx = -(J'J + lambda diag(J'J) + D)^-1 (J'r + g_extra)`` (the solve is a sparse Cholesky
  generated into the same code), the cost ``||r||^2`` and the per-term costs of
  :data:`~motion2robot.retarget.costs.FRAME_TERMS`, for frame parameters ``p`` (targets, contact
  weights, support half-planes; layout in :attr:`ProblemSpec.layout`), term weights ``w`` and
  ``lm = [lambda, D (nv), g_extra (nv), lower (n), upper (n)]`` (damping, the temporal terms and
  this frame's hinge bounds, from the solver); a hinge at a bound whose gradient points outwards
  is held (projected Newton).
- ``cost(qpos, p, w) -> (cost, terms)``: the same cost and per-term costs without the step.
- ``project(qpos, p, lm) -> (dx, violation)``: the (nearly) minimum-norm step zeroing the
  linearised hard constraints (contact, floor, balance, self-collision rows;
  :data:`~motion2robot.retarget.costs.HARD_TERMS`), hinges at a bound of ``lm``'s box held;
  iterated by the solver as the final exact correction.
- ``settle(qpos, p, lm) -> (dx, violation)``: the same without the self-collision rows (cheaper
  by two thirds): the solver's second-order correction after every LM step.
- ``violation(qpos, p) -> violation``: the squared hard-constraint residual alone.
- ``points(qpos) -> (kp (3,K), corners (3,8), com (3,1), gaps (C,))``: tracked keypoints, sole
  corners [left 0..3, right 0..3], centre of mass, and self-collision gaps (m; negative =
  penetration; one per capsule pair, one per covering sphere of a capsule-polytope pair, then
  one per joint-space cut of :mod:`~motion2robot.retarget.joint_cuts`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from motion2robot.errors import RobotConfigError
from motion2robot.retarget import native
from motion2robot.retarget.collision import CapsulePair, collision_pairs, pair_gap
from motion2robot.retarget.costs import FRAME_TERMS, HARD_TERMS
from motion2robot.retarget.terms import TERMS, Inputs
from motion2robot.retarget.terms.balance import HMAX
from motion2robot.retarget.joint_cuts import JointCut, joint_cuts
from motion2robot.robot.kinematics import TangentFrames, point_in_body
from motion2robot.robot.robot import Robot

#: Limb segments tracked by direction (SMPL22 names); pairs the robot does not map are skipped.
LIMBS: tuple[tuple[str, str], ...] = (
    ("left_hip", "left_knee"), ("left_knee", "left_ankle"), ("right_hip", "right_knee"),
    ("right_knee", "right_ankle"), ("left_shoulder", "left_elbow"), ("left_elbow", "left_wrist"),
    ("right_shoulder", "right_elbow"), ("right_elbow", "right_wrist"), ("neck", "head"),
)
#: Regularisation of the exact correction (its step tends to the minimum-norm one as this -> 0).
PROJECTION_MU = 1e-8


@dataclass(frozen=True, eq=False)
class ProblemSpec:
    """Everything robot-specific the problem needs, derived from the :class:`Robot` (no tables)."""

    robot: Robot
    n: int
    nv: int
    length: float                      # leg length (m): normaliser of position residuals
    kp_names: tuple[str, ...]
    dir_pairs: tuple[tuple[int, int], ...]
    left_local: np.ndarray             # root-body axis that points left at the nominal pose
    torso_up_local: np.ndarray         # torso-body axis that points up at the nominal pose
    foot_fwd_local: np.ndarray         # (2, 3) foot axes pointing forward at the nominal pose
    foot_up_local: np.ndarray          # (2, 3) foot axes pointing up at the nominal pose
    capsules: tuple[CapsulePair, ...]
    cuts: tuple[JointCut, ...]           # pairs one or two hinges apart, in joint space
    layout: dict[str, slice] = field(default_factory=dict)

    @property
    def n_params(self) -> int:
        return max(s.stop for s in self.layout.values())


def build_spec(robot: Robot) -> ProblemSpec:
    """Derive the problem structure of ``robot`` from its model at the nominal posture."""
    d = robot.new_data()
    names = tuple(robot.keypoints)
    idx = {k: i for i, k in enumerate(names)}
    kp_pos = d.site_xpos[robot.keypoint_sites]
    if robot.sole_sites.shape != (2, 4):
        raise RobotConfigError(f"{robot.name}: the retargeter needs both feet with 4 sole corners; add [feet.left] and [feet.right]")
    length = _leg_length(robot, kp_pos, idx)
    pairs = tuple((idx[a], idx[b]) for a, b in LIMBS if a in idx and b in idx
                  and np.linalg.norm(kp_pos[idx[b]] - kp_pos[idx[a]]) > 0.02 * length)
    rot = lambda b: d.xmat[b].reshape(3, 3)
    ez, ey, ex = np.eye(3)[2], np.eye(3)[1], np.eye(3)[0]
    feet = robot.foot_bodies
    caps = collision_pairs(robot)
    cuts = joint_cuts(robot, {tuple(sorted((c.a.body, c.b.body))) for c in caps})
    layout = _layout(len(names), len(pairs))
    return ProblemSpec(
        robot=robot, n=robot.n_joints, nv=6 + robot.n_joints, length=length, kp_names=names,
        dir_pairs=pairs, left_local=rot(robot.root_body).T @ ey, torso_up_local=rot(robot.torso_body).T @ ez,
        foot_fwd_local=np.stack([rot(b).T @ ex for b in feet]), foot_up_local=np.stack([rot(b).T @ ez for b in feet]),
        capsules=caps, cuts=cuts, layout=layout,
    )


def _leg_length(robot: Robot, kp_pos: np.ndarray, idx: dict[str, int]) -> float:
    """Hip->knee->ankle length at the nominal pose, else the root height (m)."""
    legs = []
    for s in ("left", "right"):
        ks = [f"{s}_hip", f"{s}_knee", f"{s}_ankle"]
        if all(k in idx for k in ks):
            p = kp_pos[[idx[k] for k in ks]]
            legs.append(np.linalg.norm(p[1] - p[0]) + np.linalg.norm(p[2] - p[1]))
    return float(np.mean(legs)) if legs else float(robot.nominal_qpos[2])


def _layout(k: int, dpairs: int) -> dict[str, slice]:
    sizes = [("kp_t", 3 * k), ("kp_w", k), ("dir_t", 3 * dpairs), ("dir_w", dpairs), ("pelvis_left", 3),
             ("torso_up", 3), ("foot_fwd", 6), ("foot_fwd_w", 2), ("sole_t", 24), ("sole_wz", 2),
             ("sole_wxy", 2), ("bal", 3 * HMAX), ("bal_w", 1)]
    out, at = {}, 0
    for name, size in sizes:
        out[name] = slice(at, at + size)
        at += size
    return out


def _geometry(spec: ProblemSpec, qpos, dx):
    """Tangent frames and the points every term needs, at ``qpos`` moved by tangent step ``dx``
    (to first order: exact value and Jacobian at dx = 0)."""
    rb = spec.robot
    m = rb.model
    tf = TangentFrames(m, qpos, dx)
    kp = [tf.point(int(m.site_bodyid[s]), m.site_pos[s]) for s in rb.keypoint_sites]
    corners = [tf.point(int(m.site_bodyid[s]), m.site_pos[s]) for s in rb.sole_sites.ravel()]
    bodies = [b for b in range(1, m.nbody) if m.body_mass[b] > 0 and rb.root_body in _ancestry(m, b)]
    mass = float(sum(m.body_mass[b] for b in bodies))
    com = sum(float(m.body_mass[b]) * tf.point(b, m.body_ipos[b]) for b in bodies) / mass

    def ends(c):
        return tf.point(c.body, c.p0), tf.point(c.body, c.p1)

    def ends_now(c):
        return point_in_body(tf.frames, c.body, c.p0), point_in_body(tf.frames, c.body, c.p1)

    def frame(b):
        origin = tf.point(b, np.zeros(3))
        return origin, [tf.point(b, e) - origin for e in np.eye(3)]

    gaps = [pair_gap(c, ends, ends_now, frame) for c in spec.capsules]
    for cut in spec.cuts:  # linear in the hinges (joint_cuts)
        angles = ca.vertcat(*[qpos[int(i)] + dx[int(j)] for i, j in zip(cut.qpos_index, cut.dof_index)])
        gaps.append(cut.lever * (cut.offset - ca.dot(ca.DM(cut.normal), angles)))
    return tf, kp, corners, com, gaps


def _ancestry(m, b: int) -> list[int]:
    out = []
    while b > 0:
        out.append(b)
        b = int(m.body_parentid[b])
    return out


def residuals(spec: ProblemSpec, q, dx, p, w):
    """Weighted residual vector ``r`` (cost = ||r||^2), per-term costs (list) and the unweighted
    hard-constraint rows (dict by term of :data:`~motion2robot.retarget.costs.HARD_TERMS`) at ``q``
    moved by ``dx``, for frame parameters ``p`` and term weights ``w`` (casadi SX); the terms are
    those of :data:`~motion2robot.retarget.terms.TERMS`, in order."""
    tf, kp, corners, com, gaps = _geometry(spec, q, dx)
    x = Inputs(spec, {k: p[s] for k, s in spec.layout.items()}, tf, kp, corners, com, gaps, q, dx)
    res = {t.name: t.residual(x) for t in TERMS}
    hard = {t: ca.vertcat(*res[t]) if res[t] else ca.SX.zeros(0, 1) for t in HARD_TERMS}
    r_all, terms = [], []
    for i, t in enumerate(FRAME_TERMS):
        r = ca.vertcat(*res[t]) if res[t] else ca.SX.zeros(0, 1)
        r_all.append(ca.sqrt(w[i]) * r)
        terms.append(w[i] * ca.sumsqr(r))
    return ca.vertcat(*r_all), terms, hard


def _chol_solve(A, b, order: list[int]):
    """Solve A x = b for a symmetric positive definite SX ``A`` by a Cholesky factorisation in
    the variable order ``order``; structural zeros are skipped, so with the root variables last
    (an arrow-shaped matrix: limbs do not couple) the factor stays sparse."""
    n = len(order)
    Ap = A[order, order]
    bp = b[order]
    L = [[ca.SX(0)] * n for _ in range(n)]
    for j in range(n):
        s = Ap[j, j]
        for k in range(j):
            if not L[j][k].is_zero():
                s = s - L[j][k] * L[j][k]
        L[j][j] = ca.sqrt(s)
        for i in range(j + 1, n):
            s = Ap[i, j]
            for k in range(j):
                if not (L[i][k].is_zero() or L[j][k].is_zero()):
                    s = s - L[i][k] * L[j][k]
            L[i][j] = ca.SX(0) if s.is_zero() else s / L[j][j]
    y = [ca.SX(0)] * n
    for i in range(n):
        s = bp[i]
        for k in range(i):
            if not L[i][k].is_zero():
                s = s - L[i][k] * y[k]
        y[i] = s / L[i][i]
    x = [ca.SX(0)] * n
    for i in reversed(range(n)):
        s = y[i]
        for k in range(i + 1, n):
            if not L[k][i].is_zero():
                s = s - L[k][i] * x[k]
        x[i] = s / L[i][i]
    out = [ca.SX(0)] * n
    for pos, var in enumerate(order):
        out[var] = x[pos]
    return ca.vertcat(*out)


#: casadi Function options: common subexpressions are merged (~30 % fewer instructions).
FUNCTION_OPTIONS = {"cse": True}


def build_functions(spec: ProblemSpec) -> dict[str, ca.Function]:
    """The ``step``, ``cost``, ``project``, ``settle``, ``violation`` and ``points`` casadi functions of
    ``spec`` (module docstring), by name."""
    nq, nv = spec.robot.nq, spec.nv
    q = ca.SX.sym("qpos", nq)
    dx = ca.SX.sym("dx", nv)
    p = ca.SX.sym("p", spec.n_params)
    w = ca.SX.sym("w", len(FRAME_TERMS))
    n = spec.n
    lm = ca.SX.sym("lm", 1 + 2 * nv + 2 * n)  # [lambda, extra diagonal, extra gradient, lower, upper]
    r, terms, hard = residuals(spec, q, dx, p, w)
    zero = ca.SX.zeros(nv)
    J0, r0 = ca.substitute([ca.jacobian(r, dx), r], [dx], [zero])
    terms0 = ca.substitute(ca.vertcat(*terms), dx, zero)
    H = ca.mtimes(J0.T, J0)
    g = ca.mtimes(J0.T, r0) + lm[1 + nv:1 + 2 * nv]
    # projected Newton: a hinge at a limit whose gradient pushes it outwards is held this step
    eps = 1e-9
    hq = q[7:]
    lo, hi = lm[1 + 2 * nv:1 + 2 * nv + n], lm[1 + 2 * nv + n:]
    held = ca.logic_or(ca.logic_and(hq <= lo + eps, g[6:] > 0), ca.logic_and(hq >= hi - eps, g[6:] < 0))
    free = ca.vertcat(ca.SX.ones(6), 1 - held)
    A = H + ca.diag(lm[0] * ca.diag(H) + lm[1:1 + nv])
    A = ca.diag(free) @ A @ ca.diag(free) + ca.diag(1 - free)
    step_dx = -_chol_solve(A, free * g, list(range(6, nv)) + list(range(6)))
    opts = FUNCTION_OPTIONS
    step = ca.Function("m2r_step", [q, p, w, lm], [step_dx, ca.sumsqr(r0), terms0],
                       ["qpos", "p", "w", "lm"], ["dx", "cost", "terms"], opts)
    cost = ca.Function("m2r_cost", [q, p, w], [ca.sumsqr(r0), terms0], ["qpos", "p", "w"], ["cost", "terms"], opts)
    rows = {t: ca.substitute(x, dx, zero) for t, x in hard.items()}
    jac = {t: ca.substitute(ca.jacobian(x, dx), dx, zero) for t, x in hard.items()}
    c_all = ca.vertcat(*rows.values())
    project = _projection("m2r_project", spec, q, p, lm, [jac[t] for t in HARD_TERMS], c_all)
    light = [t for t in HARD_TERMS if t != "self_collision"]
    settle = _projection("m2r_settle", spec, q, p, lm, [jac[t] for t in light], ca.vertcat(*[rows[t] for t in light]))
    violation = ca.Function("m2r_violation", [q, p], [ca.sumsqr(c_all)], ["qpos", "p"], ["violation"], opts)
    _, kp, corners, com, gaps = _geometry(spec, q, dx)
    kp0 = ca.substitute(ca.horzcat(*kp), dx, zero)
    c0 = ca.substitute(ca.horzcat(*corners), dx, zero)
    com0 = ca.substitute(com, dx, zero)
    g0 = ca.substitute(ca.vertcat(*gaps), dx, zero) if gaps else ca.SX.zeros(0, 1)
    points = ca.Function("m2r_points", [q], [kp0, c0, com0, g0], ["qpos"], ["kp", "corners", "com", "gaps"], opts)
    return {"step": step, "cost": cost, "project": project, "settle": settle, "violation": violation, "points": points}


def _projection(name: str, spec: ProblemSpec, q, p, lm, jacobians: list, c0) -> ca.Function:
    """``name(qpos, p, lm) -> (dx, violation)``: the smallest step (root position scaled by the leg
    length) that zeroes the linearised rows ``c0`` (Jacobians ``jacobians`` with respect to the
    tangent step, one block per term); hinges at a bound of ``lm``'s box do not move; ``lm[0]`` is
    extra damping. = -M Jc' (Jc M Jc')^-1 c as the damping -> 0 (M: root position scaled by L^2),
    but solved as an nv x nv arrow-shaped system instead of a dense one over all rows."""
    nv, n = spec.nv, spec.n
    Jc = ca.vertcat(*jacobians)
    hq = q[7:]
    eps = 1e-9
    bl, bh = lm[1 + 2 * nv:1 + 2 * nv + n], lm[1 + 2 * nv + n:]
    movable = ca.vertcat(ca.SX.ones(6), 1 - ca.logic_or(hq <= bl + eps, hq >= bh - eps))
    Minv = ca.DM([1.0 / spec.length ** 2] * 3 + [1.0] * (nv - 3))
    Ac = ca.mtimes(Jc.T, Jc) + ca.diag((PROJECTION_MU + lm[0]) * Minv)
    Ac = ca.diag(movable) @ Ac @ ca.diag(movable) + ca.diag(1 - movable)
    dx = -_chol_solve(Ac, movable * ca.mtimes(Jc.T, c0), list(range(6, nv)) + list(range(6)))
    return ca.Function(name, [q, p, lm], [dx, ca.sumsqr(c0)], ["qpos", "p", "lm"], ["dx", "violation"], FUNCTION_OPTIONS)


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of (..., 4) wxyz quaternions."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw], -1)


def rotvec_to_quat(v: np.ndarray) -> np.ndarray:
    """(..., 3) rotation vectors (rad) -> (..., 4) wxyz quaternions."""
    ang = np.linalg.norm(v, axis=-1, keepdims=True)
    half = 0.5 * ang
    s = np.where(ang > 1e-12, np.sin(half) / np.maximum(ang, 1e-12), 0.5)
    return np.concatenate([np.cos(half), s * v], axis=-1)


def quat_to_rotvec(q: np.ndarray) -> np.ndarray:
    """(..., 4) wxyz quaternions -> (..., 3) rotation vectors (shortest, rad)."""
    q = np.where(q[..., :1] < 0, -q, q)
    s = np.linalg.norm(q[..., 1:], axis=-1, keepdims=True)
    ang = 2 * np.arctan2(s, q[..., :1])
    return np.where(s > 1e-12, q[..., 1:] * ang / np.maximum(s, 1e-12), 2 * q[..., 1:])


def apply_step(qpos: np.ndarray, dx: np.ndarray) -> np.ndarray:
    """Move (T, nq) qpos by (T, nv) tangent steps: position add, root-local rotation, hinge add
    (the C kernel of :mod:`~motion2robot.retarget.native` when built; the same arithmetic)."""
    fast = native.apply_step(qpos, dx)
    if fast is not None:
        return fast
    out = qpos.copy()
    out[:, :3] += dx[:, :3]
    quat = quat_mul(qpos[:, 3:7], rotvec_to_quat(dx[:, 3:6]))
    out[:, 3:7] = quat / np.linalg.norm(quat, axis=1, keepdims=True)
    out[:, 7:] += dx[:, 6:]
    return out


def tangent_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(T, nv) tangent difference a - b of (T, nq) qpos (root rotation in b's local frame; the C
    kernel of :mod:`~motion2robot.retarget.native` when built: the same arithmetic, equal to the
    last bit or so (the C library's atan2))."""
    fast = native.tangent_diff(a, b)
    if fast is not None:
        return fast
    d = np.empty((a.shape[0], a.shape[1] - 1))
    d[:, :3] = a[:, :3] - b[:, :3]
    conj = b[:, 3:7] * np.array([1, -1, -1, -1])
    d[:, 3:6] = quat_to_rotvec(quat_mul(conj, a[:, 3:7]))
    d[:, 6:] = a[:, 7:] - b[:, 7:]
    return d

"""Floor reaction forces that could really happen: unilateral, inside the friction cone, on the soles.

Model (per frame): each supporting sole corner c at p_c pushes with a force f_c inside the friction
cone about the floor normal (world z), linearised as the pyramid spanned by ``EDGES`` generators
g_e = (mu cos a_e, mu sin a_e, 1): a pyramid inscribed in the circular cone |f_xy| <= mu f_z, so
every admissible force is inside the true cone (conservative by cos(pi / EDGES) at worst: 71 % of
mu along a diagonal of the 4-sided pyramid). Each foot's centre of pressure is then inside the
hull of its corners (on the sole), and torsion about the vertical is what the corners' tangential
forces make: nothing the floor could not supply.

Among the admissible forces f (24 = 8 corners x 3) the one a torque-minimising controller would use
is chosen:

    minimise ||bias - J_w C f||^2 + penalty ||wrench - A_w C f||^2 + f' R f   over admissible f,

C mapping corner forces to the two feet's wrenches [force; moment about the sole centre] (world),
J_w the hinge rows and A_w the root rows of the feet's wrench Jacobians transposed, R a small
diagonal regularisation (tangential force dearer than normal). The wrench equality is a stiff
penalty: where no admissible force supplies the required root wrench (flight, ZMP outside the
soles, not enough friction) the remainder is the residual, itself the finding.

Solver, per frame, all frames at once:
1. The unconstrained optimum, through the feet's 12 wrench unknowns: with Q = J_w'J_w + penalty
   A_w'A_w and q = J_w'bias + penalty A_w'wrench, W = C f solves (I + S Q) W = S q, S = C R^-1 C',
   and f = R^-1 C'(q - Q W): one 12 x 12 solve per frame. Where it is admissible it is the optimum.
2. Elsewhere, the non-negative QP in the generator weights (f = G lam, lam >= 0) by a primal-dual
   active-set iteration (batched solves).
3. A frame whose active set has not settled after ``PDAS_ITERATIONS`` goes to qpOASES through
   casadi. A library call per frame costs about a millisecond, 50x what the whole check may spend
   on a frame, which is why the batched steps come first; each answer satisfies the QP's
   optimality conditions, so all paths give the same optimum.
"""

from __future__ import annotations

import functools

import casadi as ca
import mujoco
import numpy as np

#: Generators of the linearised friction cone per corner.
EDGES = 4
#: Corners per sole.
CORNERS = 4
#: Primal-dual active-set passes before a frame goes to the library QP.
PDAS_ITERATIONS = 12
#: Regularisation of the generator weights relative to the smallest force regularisation: the
#: generators of one corner are redundant (4 weights for 3 force components), so the weights need
#: a tie-breaker of their own; it moves the forces by a fraction of this size.
LAMBDA_REGULARISATION = 1e-3
#: Relative tolerance of the admissibility test of the unconstrained optimum.
ADMISSIBLE_TOLERANCE = 1e-9


def cone_generators(mu: float, edges: int = EDGES) -> np.ndarray:
    """(edges, 3) generators (mu cos a, mu sin a, 1) of a pyramid inscribed in the friction cone."""
    a = 2.0 * np.pi * np.arange(edges) / edges
    return np.stack([mu * np.cos(a), mu * np.sin(a), np.ones(edges)], axis=1)


def generator_matrix(mu: np.ndarray, edges: int = EDGES) -> np.ndarray:
    """(24, 8 * edges) block-diagonal G: generator weights -> corner forces [f_x, f_y, f_z per
    corner, left corners first]; ``mu`` (2,) per foot."""
    nc = 2 * CORNERS
    G = np.zeros((3 * nc, nc * edges))
    for c in range(nc):
        G[3 * c: 3 * c + 3, edges * c: edges * (c + 1)] = cone_generators(float(mu[c // CORNERS]), edges).T
    return G


def inside_cone(f: np.ndarray, mu: np.ndarray, tol: np.ndarray | float = 0.0, edges: int = EDGES) -> np.ndarray:
    """(T, 8) bool: corner forces f (T, 8, 3) inside the inscribed pyramid of :func:`cone_generators`
    (within ``tol`` N)."""
    half = np.pi / edges
    a = 2.0 * np.pi * (np.arange(edges) + 0.5) / edges  # face normals lie between generators
    normals = np.stack([np.cos(a), np.sin(a)], axis=1)  # (edges, 2)
    reach = np.repeat(np.asarray(mu, dtype=float), CORNERS)[None, :, None] * np.cos(half) * f[..., 2:3]
    faces = f[..., :2] @ normals.T  # (T, 8, edges)
    t = np.asarray(tol, dtype=float)
    return (f[..., 2] >= -t) & np.all(faces <= reach + (t[..., None] if t.ndim else t), axis=-1)


def friction_coefficients(model: mujoco.MjModel, foot_bodies, floor_geom: int) -> np.ndarray:
    """(2,) sliding friction between each foot and the floor, as MuJoCo combines it (the larger of
    the two geoms' coefficients) over the foot body's colliding geoms."""
    out = np.zeros(2)
    for k, body in enumerate(foot_bodies):
        geoms = np.flatnonzero((model.geom_bodyid == int(body))
                               & ((model.geom_contype != 0) | (model.geom_conaffinity != 0)))
        foot = float(model.geom_friction[geoms, 0].max()) if geoms.size else 0.0
        floor = float(model.geom_friction[floor_geom, 0]) if floor_geom >= 0 else 0.0
        out[k] = max(foot, floor)
    return out


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b over the last axis (3), broadcasting (faster than np.cross on small trailing axes)."""
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def foot_wrench_rows(centres: np.ndarray, root: np.ndarray, axis: np.ndarray, anchor: np.ndarray,
                     moves: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Wrench Jacobians transposed of the two feet, each wrench [force; moment about its sole centre]
    in world axes.

    centres (T, 2, 3) sole centres; root (T, 3) root origin; axis, anchor (T, n, 3) hinge axes and
    anchors (world); moves (n, 2) bool: hinge j lies on the path to foot k. Returns
    (A_w (T, 6, 12) root wrench [force; moment about the root origin], J_w (T, n, 12) hinge torques)."""
    T, n = axis.shape[:2]
    A = np.zeros((T, 6, 12))
    J = np.zeros((T, n, 12))
    eye = np.eye(3)
    for k in range(2):
        o = 6 * k
        A[:, 0:3, o:o + 3] = eye
        A[:, 3:6, o + 3:o + 6] = eye
        d = centres[:, k] - root  # moment of a unit force e_i at d: d x e_i
        A[:, 3:6, o:o + 3] = _cross(d[:, None, :], eye[None]).transpose(0, 2, 1)
        m = moves[:, k].astype(float)[None, :, None]
        # hinge j: a . ((c - o_j) x F + M) = F . (a x (c - o_j)) + a . M
        J[:, :, o:o + 3] = _cross(axis, centres[:, None, k] - anchor) * m
        J[:, :, o + 3:o + 6] = axis * m
    return A, J


def corner_map(corners: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """(T, 12, 24) C: corner forces [f per corner, left 0-3, right 0-3] -> the feet's wrenches
    [force; moment about the sole centre] (world). corners (T, 2, 4, 3), centres (T, 2, 3)."""
    T = len(corners)
    C = np.zeros((T, 12, 24))
    eye = np.eye(3)
    r = corners - centres[:, :, None, :]  # (T, 2, 4, 3)
    for k in range(2):
        for c in range(CORNERS):
            col = 3 * (CORNERS * k + c)
            C[:, 6 * k:6 * k + 3, col:col + 3] = eye
            C[:, 6 * k + 3:6 * k + 6, col:col + 3] = _cross(r[:, k, c, None, :], eye[None]).transpose(0, 2, 1)
    return C


def solve_contact_forces(Q: np.ndarray, q: np.ndarray, C: np.ndarray, reg: np.ndarray, support: np.ndarray,
                         mu: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Admissible corner forces minimising 1/2 f'(C'QC + diag(reg))f - (C'q)'f (see the module text).

    Q (T, 12, 12), q (T, 12), C (T, 12, 24), reg (24,) > 0, support (T, 8) bool corners that may
    push, mu (2,). Returns (f (T, 8, 3), constrained (T,) bool frames whose unconstrained optimum was
    not admissible, fallback (T,) bool frames the library QP solved)."""
    T = len(q)
    on = np.repeat(support, 3, axis=1).astype(float)  # (T, 24)
    rinv = on / reg
    CR = C * rinv[:, None, :]
    S = CR @ C.transpose(0, 2, 1)
    W = np.linalg.solve(np.eye(12) + S @ Q, (S @ q[..., None]))[..., 0]
    f = rinv * (C.transpose(0, 2, 1) @ (q - (Q @ W[..., None])[..., 0])[..., None])[..., 0]
    f = f.reshape(T, 2 * CORNERS, 3)
    scale = np.abs(f).max(axis=(1, 2), initial=0.0)[:, None] * ADMISSIBLE_TOLERANCE + 1e-12
    bad = ~(inside_cone(f, mu, scale) | ~support).all(axis=1)
    fallback = np.zeros(T, dtype=bool)
    rows = np.flatnonzero(bad)
    if rows.size:
        G = generator_matrix(mu)
        Cg = C[rows] @ G
        Hf = G.T @ (reg[:, None] * G)
        H = Cg.transpose(0, 2, 1) @ Q[rows] @ Cg + Hf + LAMBDA_REGULARISATION * reg.min() * np.eye(len(Hf))
        g = (Cg.transpose(0, 2, 1) @ q[rows, :, None])[..., 0]
        lam, fb = solve_nonnegative(H, g, np.repeat(support[rows], EDGES, axis=1))
        f[rows] = (lam @ G.T).reshape(len(rows), 2 * CORNERS, 3)
        fallback[rows] = fb
    return f, bad, fallback


@functools.lru_cache(maxsize=4)
def _solver(n: int) -> ca.Function:
    return ca.conic("contact_forces", "daqp", {"h": ca.Sparsity.dense(n, n), "a": ca.Sparsity(0, n)},
                    {"error_on_fail": False})


def _masked_solve(H: np.ndarray, g: np.ndarray, on: np.ndarray) -> np.ndarray:
    """x with H_PP x_P = g_P on the variables ``on`` (T, m) bool and x = 0 elsewhere, per frame."""
    mk = on.astype(float)
    K = H * mk[:, :, None] * mk[:, None, :]
    idx = np.arange(H.shape[-1])
    K[:, idx, idx] += 1.0 - mk
    return np.linalg.solve(K, (g * mk)[..., None])[..., 0]


def _pdas(H: np.ndarray, g: np.ndarray, free: np.ndarray, x: np.ndarray, todo: np.ndarray) -> np.ndarray:
    """Primal-dual active set from all variables free: returns the frames whose set did not settle."""
    on = free.copy()
    scale = np.abs(g).max(axis=1, initial=0.0) + 1e-300
    for _ in range(PDAS_ITERATIONS):
        if todo.size == 0:
            break
        xt = _masked_solve(H[todo], g[todo], on[todo])
        grad = (H[todo] @ xt[..., None])[..., 0] - g[todo]
        new = free[todo] & np.where(on[todo], xt >= 0.0, grad < -1e-10 * scale[todo, None])
        x[todo] = xt
        changed = (new != on[todo]).any(axis=1)
        on[todo] = new
        todo = todo[changed]
    return todo


def _lawson_hanson(H: np.ndarray, g: np.ndarray, free: np.ndarray, x: np.ndarray, todo: np.ndarray) -> np.ndarray:
    """Lawson-Hanson active set from x = 0: one variable freed per pass, each frame stepped back
    onto the bounds when a free variable would turn negative (finite, no cycling). Returns the
    frames not finished within the pass limit."""
    m = g.shape[1]
    x[todo] = 0.0
    on = np.zeros_like(free)
    scale = np.abs(g).max(axis=1, initial=0.0) + 1e-300
    for _ in range(4 * m):
        if todo.size == 0:
            break
        w = g[todo] - (H[todo] @ x[todo][..., None])[..., 0]  # minus the gradient
        w = np.where(free[todo] & ~on[todo], w, -np.inf)
        k = np.argmax(w, axis=1)
        grow = w[np.arange(todo.size), k] > 1e-10 * scale[todo]
        todo, k = todo[grow], k[grow]  # the others satisfy the optimality conditions
        on[todo, k] = True
        inner = todo
        for _ in range(m):
            if inner.size == 0:
                break
            z = _masked_solve(H[inner], g[inner], on[inner])
            neg = on[inner] & (z <= 0.0)
            ok = ~neg.any(axis=1)
            x[inner[ok]] = z[ok]
            inner, z, neg = inner[~ok], z[~ok], neg[~ok]
            if inner.size == 0:
                break
            xb = x[inner]
            gap = xb - z
            ratio = np.where(neg & (gap > 0), xb / np.where(gap > 0, gap, 1.0), np.where(neg, 0.0, np.inf))
            xb = xb + ratio.min(axis=1, keepdims=True) * (z - xb)
            x[inner] = xb
            on[inner] &= xb > 1e-14 * scale[inner, None]
    return todo


def solve_nonnegative(H: np.ndarray, g: np.ndarray, free: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """argmin_x 1/2 x'Hx - g'x subject to x >= 0 and x_i = 0 where not ``free``, per frame.

    H (T, m, m) positive definite, g (T, m), free (T, m) bool. Returns (x (T, m), fallback (T,) bool
    frames that the library QP solved). Batched: a primal-dual active-set iteration first (a few
    solves when it settles), Lawson-Hanson for the frames where it cycles, DAQP (through casadi)
    for any frame still open."""
    T, m = g.shape
    x = np.zeros((T, m))
    todo = _pdas(H, g, free, x, np.flatnonzero(free.any(axis=1)))
    if todo.size:
        todo = _lawson_hanson(H, g, free, x, todo)
    fallback = np.zeros(T, dtype=bool)
    if todo.size:
        fallback[todo] = True
        solver = _solver(m)
        for t in todo:
            res = solver(h=H[t], g=-g[t], lbx=np.zeros(m), ubx=np.where(free[t], np.inf, 0.0))
            x[t] = np.asarray(res["x"]).ravel()
    return np.maximum(x, 0.0) * free, fallback

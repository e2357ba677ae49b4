"""Per-frame tracking of a walking pattern: the root and the leg hinges that put every sole corner
on its plan and the CoM on its path, and the root height the legs reach.

Units: metres, radians; world frame z up; quaternions wxyz.
"""

from __future__ import annotations

import functools

import mujoco
import numpy as np

from motion2robot.retarget import tracker_kernel
from motion2robot.retarget.smoothing import low_pass
from motion2robot.robot.chains import foot_ancestor_mask, hip_hinges
from motion2robot.robot.poses import frame_poses
from motion2robot.robot.robot import Robot

#: Hz, cutoff of the root height (its per-step dips go).
HEIGHT_CUTOFF_HZ = 1.5
#: The farthest a hip may be from its sole's centre, as a fraction of that distance with the leg
#: straight: knees stay bent, away from the straight-knee singularity.
REACH = 0.93
#: s, half-width of the running minimum under the root height's bound (:func:`_envelope_below`).
HEIGHT_WINDOW_S = 0.4
#: Levenberg-Marquardt iterations per frame at most (warm-started), and the step (m or rad) below
#: which a frame has converged.
IK_ITERATIONS = 8
STEP_TOLERANCE = 1e-6
#: Weight of the CoM rows against the sole corners' rows (metres against metres).
COM_WEIGHT = 1.0
#: Weight of the targets (sole corners, CoM) against the soft rows below: the soft rows decide only
#: what the targets leave free (a planted sole held to 0.01 of what a soft row pulls).
HARD_WEIGHT = 100.0
#: Weights of the soft rows keeping the root near its planned height (m per m) and orientation
#: (m per rad).
ROOT_HEIGHT_WEIGHT = 0.3
ROOT_TURN_WEIGHT = 0.05
#: rad, and m: the zone before each leg hinge's limit in which it is eased towards it, and the
#: soft row's value at the limit.
LIMIT_ZONE = 0.15
LIMIT_WEIGHT = 0.05
#: s: a frame's change from the one before weighs (m per rad, per m) TEMPORAL_TIME x fps, i.e.
#: a speed of 1 rad/s or 1 m/s costs like TEMPORAL_TIME m of a target missed.
TEMPORAL_TIME = 0.002
#: Rows of the targets (8 sole corners x 3, the CoM's x and y): the tracking error is over them.
HARD_ROWS = 26
#: m: a target missed by more than this loses the frames after it (the attempt fails its checks).
LOST = 0.05
#: Least damping of the steps (m^2).
DAMPING = 1e-8
#: Largest change of any unknown in one step (m or rad).
MAX_STEP = 0.2


def _envelope_below(bound: np.ndarray, width: int, fps: float) -> np.ndarray:
    """A C2-smooth curve at or below ``bound`` (T,) (within 0.1 mm): a running minimum over
    ``width`` frames either side, low-passed at HEIGHT_CUTOFF_HZ, lowered where it still exceeds
    the bound and low-passed again (a few rounds)."""
    T = len(bound)
    pad = np.pad(bound, width, mode="edge")
    env = np.lib.stride_tricks.sliding_window_view(pad, 2 * width + 1).min(axis=1)[:T]
    out = env
    for _ in range(8):
        out = low_pass(env[:, None], fps, HEIGHT_CUTOFF_HZ)[:, 0]
        over = out - bound
        if over.max() <= 1e-4:
            break
        env = env - np.maximum(over, 0.0) - 1e-4
    return out


class LegTracker:
    """Per-frame Levenberg-Marquardt on the root pose and the leg hinges of ``robot`` (MuJoCo
    Jacobians of the sole corner sites and of the whole-body CoM): the sole corners on their
    targets and the CoM on its path (hard, in the least-squares sense), the root's height and
    orientation near the planned ones (soft rows, ROOT_HEIGHT_WEIGHT and ROOT_TURN_WEIGHT), so a
    leg at a joint limit is helped by the root tilting or dropping a little, continuously.

    The rows (``self.n_rows``): the 8 sole corners' x, y, z and the CoM's x, y (HARD_ROWS, scaled
    by HARD_WEIGHT), the root height (1), the root orientation (3), one limit row per leg hinge,
    then, past a sequence's first frame, one temporal row per unknown. The unknowns
    (``self.cols``): the root's velocity (3 world m, 3 rad about world axes, as ``mj_jac``'s
    columns) and the leg hinges' (rad). Every soft row has a single unknown, so the Jacobian is
    one preallocated matrix whose soft part is written once per ``solve`` (the limit rows'
    diagonal per evaluation); the work arrays are allocated once, with views of their parts, and
    the normal equations are solved by a Cholesky factorisation."""

    def __init__(self, robot: Robot) -> None:
        self.robot, self.model = robot, robot.model
        self.data = d = mujoco.MjData(robot.model)
        legs = foot_ancestor_mask(robot).any(axis=1)
        self.legs = np.flatnonzero(legs)
        self.qadr = robot.model.jnt_qposadr[np.asarray(robot.joint_ids)[self.legs]]
        self.dadr = robot.model.jnt_dofadr[np.asarray(robot.joint_ids)[self.legs]]
        self.cols = np.concatenate([np.arange(6), self.dadr])
        self.first = hip_hinges(robot)
        self.lo, self.hi = robot.lower[self.legs], robot.upper[self.legs]
        self.sites = np.asarray(robot.sole_sites).ravel()
        n, nc = len(self.legs), len(self.cols)
        self.n_rows = HARD_ROWS + 4 + n + nc
        # the leg hinges' qpos entries: a slice when consecutive (views, no copies), else indices
        a = int(self.qadr[0]) if n else 0
        self._legq = slice(a, a + n) if np.array_equal(self.qadr, np.arange(a, a + n)) else self.qadr
        # a hinge's limit row is q - clip(q, lo + zone, hi - zone) when the zones do not overlap
        self._lo_zone, self._hi_zone = self.lo + LIMIT_ZONE, self.hi - LIMIT_ZONE
        self._zones_apart = bool((self._lo_zone <= self._hi_zone).all())
        self._w_hard = np.r_[np.full(24, HARD_WEIGHT), np.full(2, HARD_WEIGHT * COM_WEIGHT)]
        self._w_hard_col = self._w_hard[:, None]
        # each row's weight (a limit row is computed as over x its derivative: 0.5; temporal: per solve)
        self._w_rows = np.r_[self._w_hard, ROOT_HEIGHT_WEIGHT, np.full(3, ROOT_TURN_WEIGHT), np.full(n, 0.5), np.ones(nc)]
        self._w_first = self._w_rows[:HARD_ROWS + 4 + n]
        # views of MjData's arrays (they live as long as it does) and of the step's parts
        self._qpos, self._sxp, self._com = d.qpos, d.site_xpos, d.subtree_com[robot.root_body, :2]
        self._qpos_pos, self._qpos_quat = d.qpos[:3], d.qpos[3:7]
        self._qpos_legs = d.qpos[self._legq] if isinstance(self._legq, slice) else None
        self._at_lo, self._at_hi = self.lo + 1e-9, self.hi - 1e-9
        # the Jacobian over the unknowns: hard rows from the sites' and the CoM's whole-nv rows
        self._jac = np.zeros((HARD_ROWS + 1, robot.model.nv))
        self._jac_hard = self._jac[:HARD_ROWS]
        self._site_jac = [(self._jac[3 * i:3 * i + 3], int(s)) for i, s in enumerate(self.sites)]
        self._com_jac = self._jac[24:27]
        self._J = J = np.zeros((self.n_rows, nc))
        self._J_hard, self._J_limit = J[:HARD_ROWS], J.reshape(-1)[30 * nc + 6::nc + 1][:n]
        self._J_rows = {rows: J[:rows] for rows in (self.n_rows, self.n_rows - nc)}
        self._H, self._L, self._g, self._dx = np.zeros((nc, nc)), np.zeros((nc, nc)), np.zeros(nc), np.zeros(nc)
        self._dx_pos, self._dx_rot, self._dx_legs, self._dx_abs = self._dx[:3], self._dx[3:6], self._dx[6:], np.zeros(nc)
        self._L_diag = self._L.reshape(-1)[::nc + 1]
        self._held = np.zeros(nc, dtype=bool)
        self._r_abs = np.zeros(HARD_ROWS)
        self._over, self._t1, self._t2, self._leg = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
        k = 30 + n  # per residual buffer: (all, first frame's, corners (8, 3), CoM, hard, turn, limits,
        #           temporal: pos, turn, legs)
        self._r = [(r, r[:k], r[:24].reshape(8, 3), r[24:26], r[:HARD_ROWS], r[27:30], r[30:k], r[k:k + 3],
                    r[k + 3:k + 6], r[k + 6:]) for r in (np.zeros(self.n_rows), np.zeros(self.n_rows))]

    def _residual(self, r: tuple, corners: np.ndarray, com_xy: np.ndarray, plan_z: float, plan_quat: np.ndarray,
                  prev: tuple | None, w_prev: float) -> float:
        """Kinematics at ``self.data.qpos``, then the rows into the buffer ``r`` (a tuple of views
        of it, ``self._r``): the sole corners on ``corners`` (8, 3) and the CoM on ``com_xy`` (2,)
        first, then the soft rows (the root near ``plan_z`` and ``plan_quat``, the temporal rows
        only with ``prev`` = the previous frame's (root position, quaternion, leg hinges)); the
        limit rows' derivatives go to the Jacobian. Returns the cost (sum of squared rows)."""
        m, d, qpos = self.model, self.data, self._qpos
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        r_all, r_first, r_corners, r_com, r_hard, r_turn, r_limit, r_pos, r_rot, r_legs = r
        np.subtract(self._sxp[self.sites], corners, r_corners)
        np.subtract(self._com, com_xy, r_com)
        # soft: the root near its planned height and orientation
        r_all[26] = qpos[2] - plan_z
        mujoco.mju_subQuat(r_turn, qpos[3:7], plan_quat)
        # a hinge closing on a limit is eased into it: over the last LIMIT_ZONE rad a cost growing
        # as the 4th power of the depth, whose curvature starts from zero (so the solution's speed
        # and acceleration stay continuous where a hinge enters the zone; with a quadratic cost its
        # speed jumped there, a spike a finer frame rate shows taller)
        q = qpos[self._legq]
        over, t1, t2 = self._over, self._t1, self._t2
        if self._zones_apart:  # the depth past the zone's edge, signed
            np.subtract(q, np.minimum(np.maximum(q, self._lo_zone, out=t1), self._hi_zone, out=t1), over)
        else:
            np.maximum(np.subtract(q, self._hi_zone, t1), 0.0, out=t1)
            np.maximum(np.subtract(self._lo_zone, q, t2), 0.0, out=t2)
            np.subtract(t1, t2, over)
        # the row LIMIT_WEIGHT sign(over) over^2 / LIMIT_ZONE is 0.5 over x its derivative (the
        # 0.5 is the row's weight)
        np.multiply(np.abs(over, t1), 2.0 * LIMIT_WEIGHT / LIMIT_ZONE, self._J_limit)
        np.multiply(over, self._J_limit, r_limit)
        if prev is None:
            np.multiply(r_first, self._w_first, r_first)
            return mujoco.mju_dot(r_first, r_first)  # MuJoCo's sum, as the C loop's
        # the previous frame's solution: the continuous branch, no jumps
        np.subtract(qpos[:3], prev[0], r_pos)
        mujoco.mju_subQuat(r_rot, qpos[3:7], prev[1])
        np.subtract(q, prev[2], r_legs)
        np.multiply(r_all, self._w_rows, r_all)
        return mujoco.mju_dot(r_all, r_all)

    def _normal(self, r: np.ndarray) -> None:
        """The Gauss-Newton normal equations of the rows ``r`` (all, or a first frame's) at the posture in
        ``self.data`` (its kinematics and the limit rows' derivatives done by the evaluation of
        ``r``): ``self._H`` = J^T J, ``self._g`` = -J^T r."""
        m, d = self.model, self.data
        for jac, site in self._site_jac:
            mujoco.mj_jacSite(m, d, jac, None, site)
        mujoco.mj_jacSubtreeCom(m, d, self._com_jac, self.robot.root_body)
        self._jac_hard.take(self.cols, 1, self._J_hard)
        np.multiply(self._J_hard, self._w_hard_col, self._J_hard)
        A = self._J_rows[len(r)]
        mujoco.mju_mulMatTMat(self._H, A, A)
        mujoco.mju_mulMatTVec(self._g, A, r)
        np.negative(self._g, self._g)

    def _direction(self, at_lo: np.ndarray | None, at_hi: np.ndarray, mu: float) -> tuple[np.ndarray, float]:
        """The damped Gauss-Newton step from ``self._H``, ``self._g``, and its largest entry's
        size. With ``at_lo``/``at_hi`` (the leg hinges at a limit; None: none), hinges that the
        step would push further out are held (their rows and columns of the normal matrix made the
        identity's and their right-hand side zero, i.e. the step solved again without them: the
        others, the root's roll included, take over). The largest change is capped at MAX_STEP."""
        L, dx, g = self._L, self._dx, self._g
        np.copyto(L, self._H)
        self._L_diag += mu
        mujoco.mju_cholFactor(L, 0.0)
        mujoco.mju_cholSolve(dx, L, g)
        if at_lo is not None:
            held = self._held
            held.fill(False)
            for _ in range(2):
                step = dx[6:]
                out = (at_lo & (step < 0)) | (at_hi & (step > 0))
                if not np.count_nonzero(out):
                    break
                held[6:] |= out
                np.copyto(L, self._H)
                self._L_diag += mu
                L[held, :] = 0.0
                L[:, held] = 0.0
                L[held, held] = 1.0
                mujoco.mju_cholFactor(L, 0.0)
                mujoco.mju_cholSolve(dx, L, np.where(held, 0.0, g))
        big = float(np.maximum.reduce(np.abs(dx, self._dx_abs)))
        if big > MAX_STEP:
            dx *= MAX_STEP / big
            big = MAX_STEP
        return dx, big

    def _step(self, q: np.ndarray) -> None:
        """``self.data.qpos`` = ``q`` moved by the step ``self._dx`` (the root's velocity and
        the leg hinges'), the hinges kept within their limits."""
        np.copyto(self._qpos, q)
        np.add(self._qpos_pos, self._dx_pos, self._qpos_pos)
        mujoco.mju_quatIntegrate(self._qpos_quat, self._dx_rot, 1.0)
        legs = self._qpos_legs
        if legs is None:  # scattered leg hinges
            legs = self._leg
            np.add(q[self._legq], self._dx_legs, legs)
        else:
            np.add(legs, self._dx_legs, legs)
        np.minimum(np.maximum(legs, self.lo, out=legs), self.hi, out=legs)
        if self._qpos_legs is None:
            self._qpos[self._legq] = legs

    def solve(self, Q: np.ndarray, corners: np.ndarray, com_xy: np.ndarray, fps: float,
              start: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Q (T, nq) at ``fps`` with the root and the leg hinges solved so the sole corners reach
        ``corners`` (T, 2, 4, 3) and the CoM ``com_xy`` (T, 2), the root staying near Q's height
        and orientation and each frame near the one before (TEMPORAL_TIME); the other hinges are
        kept. ``start``: a trajectory to start each frame from (a previous round's answer;
        default the previous frame's). Returns it and each frame's largest distance of a sole
        corner or the CoM from its target (m)."""
        out = Q.copy()
        err = np.zeros(len(Q))
        qpos, legq, nc = self._qpos, self._legq, len(self.cols)
        targets = np.asarray(corners, float).reshape(len(Q), 8, 3)
        w_prev = TEMPORAL_TIME * fps
        J = self._J  # the soft rows' constant part: one unknown per row
        J[HARD_ROWS:] = 0.0
        J[26, 2] = ROOT_HEIGHT_WEIGHT
        J[27:30, 3:6] = ROOT_TURN_WEIGHT * np.eye(3)
        J[self.n_rows - nc:] = w_prev * np.eye(nc)
        self._w_rows[self.n_rows - nc:] = w_prev
        native = self._native(Q, corners, com_xy, start)
        if native is not None:
            return native
        lo_buf, hi_buf = np.zeros(len(self.legs), dtype=bool), np.zeros(len(self.legs), dtype=bool)
        for t in range(len(Q)):
            q = Q[t].copy()
            p = out[t - 1]
            prev = (p[:3], p[3:7], p[legq]) if t else None
            if start is not None:
                s = start[t]
                q[:7], q[legq] = s[:7], s[legq]
            elif t:  # the previous frame's root xy and legs
                q[:2], q[legq] = p[:2], prev[2]
            rows = 0 if t else 1  # which view of a residual buffer the normal equations take
            frame = (targets[t], com_xy[t], float(Q[t, 2]), Q[t, 3:7], prev, w_prev)
            r, r_new = self._r
            np.copyto(qpos, q)
            cost, mu, fresh = self._residual(r, *frame), DAMPING, False
            for _ in range(IK_ITERATIONS):
                if not fresh:  # the normal equations at the current solution (kinematics in data)
                    self._normal(r[rows])
                    ql = q[legq]
                    at_lo, at_hi = np.less_equal(ql, self._at_lo, lo_buf), np.greater_equal(ql, self._at_hi, hi_buf)
                    if not (np.count_nonzero(at_lo) or np.count_nonzero(at_hi)):
                        at_lo = None
                    fresh = True
                dx, big = self._direction(at_lo, at_hi, mu)
                self._step(q)
                c_new = self._residual(r_new, *frame)
                if c_new < cost:  # keep a step that lowers the cost
                    done = big < STEP_TOLERANCE or cost - c_new < 1e-12 * HARD_WEIGHT ** 2
                    np.copyto(q, qpos)
                    r, r_new, cost, mu, fresh = r_new, r, c_new, max(mu / 10.0, DAMPING), False
                    if done:
                        break
                else:
                    mu *= 100.0
            err[t] = float(np.maximum.reduce(np.abs(r[4], self._r_abs))) / HARD_WEIGHT
            out[t] = q
            if err[t] > LOST:  # the pattern is out of the legs' reach: the rest is not worth solving
                err[t:] = err[t]
                break
        return out, err

    def _native(self, Q: np.ndarray, corners: np.ndarray, com_xy: np.ndarray,
                start: np.ndarray | None) -> tuple[np.ndarray, np.ndarray] | None:
        """``solve``'s frame loop in C (:mod:`~.tracker_kernel`, the same steps), once ``solve`` has
        laid out the soft rows and the weights; None without the compiled loop."""
        i32 = functools.partial(np.ascontiguousarray, dtype=np.int32)
        ints = i32([self.model.nq, self.model.nv, len(self.legs), self.robot.root_body, self._zones_apart,
                    IK_ITERATIONS])
        consts = np.array([2.0 * LIMIT_WEIGHT / LIMIT_ZONE, STEP_TOLERANCE, 1e-12 * HARD_WEIGHT ** 2, DAMPING,
                           MAX_STEP, HARD_WEIGHT, LOST])
        limits = tuple(np.ascontiguousarray(a, dtype=np.float64) for a in (self.lo, self.hi, self._lo_zone, self._hi_zone))
        return tracker_kernel.track(self.model, self.data, ints, i32(self.qadr), i32(self.cols), i32(self.sites),
                                    limits, self._w_rows, consts, self._J, Q, start,
                                    np.reshape(corners, (len(Q), 24)), com_xy)

    def hips(self, Q: np.ndarray) -> np.ndarray:
        """(T, 2, 3) world positions (m) of each leg's first hinge (its hip) in the frames of Q."""
        joints = [int(self.robot.joint_ids[j]) for j in self.first]
        return frame_poses(self.model, Q, joints=joints).anchors

    def straight_reach(self) -> np.ndarray:
        """(2,) distance (m) from each leg's hip to its sole centre with the leg straight (its
        hinges at zero, or at the limit nearest zero)."""
        m, d, rb = self.model, self.data, self.robot
        d.qpos[:] = rb.nominal_qpos
        d.qpos[self.qadr] = np.clip(0.0, self.lo, self.hi)
        mujoco.mj_kinematics(m, d)
        return np.array([np.linalg.norm(d.xanchor[rb.joint_ids[self.first[f]]] - d.site_xpos[rb.sole_center_sites[f]])
                         for f in range(2)])


def root_height(tracker: LegTracker, Q: np.ndarray, corners: np.ndarray, fps: float) -> np.ndarray:
    """(T,) C2-smooth root heights (m) at or below Q's, low enough that every hip stays within
    REACH of its straight-leg distance to its sole's planned centre (``corners`` (T, 2, 4, 3)):
    lowering the root lowers the hips with it, the horizontal distance stays."""
    reach = REACH * tracker.straight_reach()
    hips = tracker.hips(Q)                                               # (T, 2, 3)
    sole = corners.mean(axis=2)                                          # (T, 2, 3)
    horiz = np.linalg.norm(hips[..., :2] - sole[..., :2], axis=-1)
    vert = np.sqrt(np.maximum(reach ** 2 - horiz ** 2, 0.0))
    drop = np.maximum(0.0, (hips[..., 2] - sole[..., 2]) - vert).max(axis=1)
    return _envelope_below(Q[:, 2] - drop, max(1, int(round(HEIGHT_WINDOW_S * fps))), fps)

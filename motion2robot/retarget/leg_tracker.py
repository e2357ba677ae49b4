"""Per-frame tracking of a walking pattern: the root and the leg hinges that put every sole corner
on its plan and the CoM on its path, and the root height the legs reach.

Units: metres, radians; world frame z up; quaternions wxyz.
"""

from __future__ import annotations

import mujoco
import numpy as np

from motion2robot.retarget.smoothing import low_pass
from motion2robot.robot.chains import foot_ancestor_mask, hip_hinges
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
    leg at a joint limit is helped by the root tilting or dropping a little, continuously."""

    def __init__(self, robot: Robot) -> None:
        self.robot, self.model = robot, robot.model
        self.data = mujoco.MjData(robot.model)
        legs = foot_ancestor_mask(robot).any(axis=1)
        self.legs = np.flatnonzero(legs)
        self.qadr = robot.model.jnt_qposadr[np.asarray(robot.joint_ids)[self.legs]]
        self.dadr = robot.model.jnt_dofadr[np.asarray(robot.joint_ids)[self.legs]]
        self.cols = np.concatenate([np.arange(6), self.dadr])
        self.first = hip_hinges(robot)
        self.lo, self.hi = robot.lower[self.legs], robot.upper[self.legs]
        self.jacp, self.jacr = np.zeros((3, robot.model.nv)), np.zeros((3, robot.model.nv))
        self.turn = np.zeros(3)
        self.sites = np.asarray(robot.sole_sites).ravel()
        self.n_rows = HARD_ROWS + 4 + len(self.legs) + len(self.cols)
        nc = len(self.cols)
        self.wxr = np.zeros((4, 3, nc))
        self.eye = np.eye(nc)
        self.turn_block = ROOT_TURN_WEIGHT * np.eye(3)
        self.limit_rows = 30 + np.arange(len(self.legs))
        self.limit_cols = 6 + np.arange(len(self.legs))

    def _residual(self, corners: np.ndarray, com_xy: np.ndarray, plan_q: np.ndarray, prev: np.ndarray | None,
                  w_prev: float) -> tuple[np.ndarray, np.ndarray]:
        """Rows and Jacobian (over root dofs and leg hinges) at ``self.data.qpos``: the sole corners
        on ``corners`` (2, 4, 3) and the CoM on ``com_xy`` (2,) (HARD_ROWS rows), then the soft rows."""
        m, d, rb = self.model, self.data, self.robot
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        nc = len(self.cols)
        n_rows = self.n_rows if prev is not None else self.n_rows - nc
        r = np.empty(n_rows)
        J = np.zeros((n_rows, nc))
        pos = d.site_xpos[self.sites]                                            # (8, 3)
        r[:24] = HARD_WEIGHT * (pos - corners.reshape(8, 3)).ravel()
        wxr = self.wxr
        for f in range(2):  # a corner moves with its foot: v = v_body + w x (p - body origin)
            body = int(rb.foot_bodies[f])
            mujoco.mj_jacBody(m, d, self.jacp, self.jacr, body)
            arm = pos[4 * f:4 * f + 4] - d.xpos[body]
            jp, jr = self.jacp[:, self.cols], self.jacr[:, self.cols]
            ax, ay, az = arm[:, 0:1], arm[:, 1:2], arm[:, 2:3]
            np.subtract(ay * jr[2], az * jr[1], out=wxr[:, 0])
            np.subtract(az * jr[0], ax * jr[2], out=wxr[:, 1])
            np.subtract(ax * jr[1], ay * jr[0], out=wxr[:, 2])
            J[12 * f:12 * f + 12] = HARD_WEIGHT * (jp[None] - wxr).reshape(12, nc)
        r[24:26] = HARD_WEIGHT * COM_WEIGHT * (d.subtree_com[rb.root_body, :2] - com_xy)
        mujoco.mj_jacSubtreeCom(m, d, self.jacp, rb.root_body)
        J[24:26] = HARD_WEIGHT * COM_WEIGHT * self.jacp[:2, self.cols]
        # soft: the root near its planned height and orientation
        r[26] = ROOT_HEIGHT_WEIGHT * (d.qpos[2] - plan_q[2])
        J[26, 2] = ROOT_HEIGHT_WEIGHT
        mujoco.mju_subQuat(self.turn, d.qpos[3:7], plan_q[3:7])
        r[27:30] = ROOT_TURN_WEIGHT * self.turn
        J[27:30, 3:6] = self.turn_block
        # a hinge closing on a limit is eased into it: over the last LIMIT_ZONE rad a cost growing
        # as the 4th power of the depth, whose curvature starts from zero (so the solution's speed
        # and acceleration stay continuous where a hinge enters the zone; with a quadratic cost its
        # speed jumped there, a spike a finer frame rate shows taller)
        q = d.qpos[self.qadr]
        over = np.maximum(q - (self.hi - LIMIT_ZONE), 0.0) - np.maximum((self.lo + LIMIT_ZONE) - q, 0.0)
        n = len(self.legs)
        r[30:30 + n] = LIMIT_WEIGHT * np.sign(over) * over ** 2 / LIMIT_ZONE
        J[self.limit_rows, self.limit_cols] = 2.0 * LIMIT_WEIGHT * np.abs(over) / LIMIT_ZONE
        if prev is not None:  # the previous frame's solution: the continuous branch, no jumps
            mujoco.mju_subQuat(self.turn, d.qpos[3:7], prev[3:7])
            k = 30 + n
            r[k:k + 3] = w_prev * (d.qpos[:3] - prev[:3])
            r[k + 3:k + 6] = w_prev * self.turn
            r[k + 6:] = w_prev * (q - prev[self.qadr])
            J[k:, :] = w_prev * self.eye
        return r, J

    def _direction(self, q: np.ndarray, J: np.ndarray, r: np.ndarray, mu: float, eye: np.ndarray) -> np.ndarray:
        """The damped Gauss-Newton step, hinges at a limit that the step would push further out
        held (their columns dropped and the step solved again: the others, the root's roll
        included, take over), the largest change capped at MAX_STEP."""
        free = np.ones(len(eye), dtype=bool)
        for _ in range(3):
            A = J[:, free]
            dx = np.zeros(len(eye))
            dx[free] = np.linalg.solve(A.T @ A + mu * np.eye(int(free.sum())), -A.T @ r)
            qj = q[self.qadr]
            out = ((qj <= self.lo + 1e-9) & (dx[6:] < 0)) | ((qj >= self.hi - 1e-9) & (dx[6:] > 0))
            if not out.any():
                break
            free[6:] &= ~out
        return dx * min(1.0, MAX_STEP / max(float(np.abs(dx).max()), 1e-12))

    def _step(self, q: np.ndarray, dx: np.ndarray) -> np.ndarray:
        out = q.copy()
        out[:3] += dx[:3]
        mujoco.mju_quatIntegrate(out[3:7], dx[3:6], 1.0)
        out[self.qadr] = np.clip(out[self.qadr] + dx[6:], self.lo, self.hi)
        return out

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
        d = self.data
        eye = np.eye(len(self.cols))
        w_prev = TEMPORAL_TIME * fps
        for t in range(len(Q)):
            q = Q[t].copy()
            prev = out[t - 1] if t else None
            if start is not None:
                q[:7], q[self.qadr] = start[t, :7], start[t, self.qadr]
            elif prev is not None:  # the previous frame's root xy and legs
                q[:2], q[self.qadr] = prev[:2], prev[self.qadr]
            d.qpos[:] = q
            r, J = self._residual(corners[t], com_xy[t], Q[t], prev, w_prev)
            cost, mu = float(r @ r), DAMPING
            for _ in range(IK_ITERATIONS):
                dx = self._direction(q, J, r, mu, eye)
                d.qpos[:] = self._step(q, dx)
                r_new, J_new = self._residual(corners[t], com_xy[t], Q[t], prev, w_prev)
                c_new = float(r_new @ r_new)
                if c_new < cost:  # keep a step that lowers the cost
                    done = np.abs(dx).max() < STEP_TOLERANCE or cost - c_new < 1e-12 * HARD_WEIGHT ** 2
                    q, r, J, cost, mu = d.qpos.copy(), r_new, J_new, c_new, max(mu / 10.0, DAMPING)
                    if done:
                        break
                else:
                    mu *= 100.0
            err[t] = float(np.abs(r[:HARD_ROWS]).max()) / HARD_WEIGHT
            out[t] = q
            if err[t] > LOST:  # the pattern is out of the legs' reach: the rest is not worth solving
                err[t:] = err[t]
                break
        return out, err

    def hips(self, Q: np.ndarray) -> np.ndarray:
        """(T, 2, 3) world positions (m) of each leg's first hinge (its hip) in the frames of Q."""
        m, d, rb = self.model, self.data, self.robot
        joints = [int(rb.joint_ids[j]) for j in self.first]
        out = np.zeros((len(Q), 2, 3))
        for t in range(len(Q)):
            d.qpos[:] = Q[t]
            mujoco.mj_kinematics(m, d)
            out[t] = d.xanchor[joints]
        return out

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

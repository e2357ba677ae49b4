"""How much of a change of its targets the retargeter passes on, and the inverse of that: the
preconditioner of the target correction (step 6 of :mod:`motion2robot.projection`).

The whole-body solve (:mod:`~motion2robot.retarget.solver`) makes a few block-Jacobi
Levenberg-Marquardt iterations per stage (``RetargetOptions.iterations``: the free-feet stage,
then the pinned one), each frame's step damped by the majorising diagonal D of the temporal terms
(4 w_v + 16 w_a per coordinate, the weights at the clip's rate; root translation divided by the
leg length squared). Linearised at a robot motion, for a change of the targets that is smooth in
time (the temporal gradient then vanishes), one iteration leaves ``M e`` of a frame's error e,
``M = (H + D)^-1 D``, H the Gauss-Newton Hessian of the tracking terms: keypoints, limb
directions, posture, and in the pinned stage the planted soles' corners (hard rows). After the
free stage's n1 iterations and the pinned stage's n2, the share of a target change that reaches
the output is ``G = I - M_p^n2 M_f^n1`` (per frame, nv x nv, tangent space). On the Bandai bow at
30 fps the model's share (mean over frames) is 0.24 for the head tilt and 0.41 for the left elbow;
moving ``human'`` along the keypoint image of either joint's change passes on 0.22 and 0.37 of it.
It is near 1 where the keypoints hold a joint firmly, 0.01 for the head pan (the head keypoint
sits almost on its axis).

A plain correction round moves ``human'`` by the keypoint image of the gap d between the robot
motion and its retargeting and gets back about ``G d``: the rounds crawl where G is small. Aimed
at the image of ``G^-1 d`` instead, they get back d where the model holds. The inverse is damped,
``(1 + mu) (G + mu I)^-1`` (at most ``1 + 1/mu`` times the plain step): the later stages (servo
rounds, smoothing, the ZMP stage) and the temporal terms' resistance to fast changes are not in
the model, and the correction raises ``mu`` when a round overshoots (:func:`~.correction.refine`).

Units: metres, radians; MuJoCo's tangent space (free joint: world translation, local rotation).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from motion2robot.retarget.costs import Weights
from motion2robot.retarget.problem import ProblemSpec, apply_step, build_spec, tangent_diff
from motion2robot.retarget.setup import rate_weights
from motion2robot.robot.chains import foot_ancestor_mask
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion


@dataclass(frozen=True)
class Attenuation:
    """share: (T, nv, nv) the share G of a smooth change of the targets that reaches the output,
    per frame of ``motion`` (the robot motion it was linearised at)."""

    motion: RobotMotion
    share: np.ndarray

    def aim(self, current: RobotMotion, mu: float) -> RobotMotion:
        """The robot motion a correction round should map back to get ``current`` (the retargeting
        of this round's ``human'``) to :attr:`motion`: ``motion (+) ((1 + mu) (G + mu I)^-1 d - d)``,
        d = ``motion (-) current`` per frame (tangent space). ``mu`` > 0 damps the inverse."""
        m = self.motion
        if current.qpos.shape != m.qpos.shape:
            raise ValueError(f"the retargeting has {current.num_frames} frames, the robot motion {m.num_frames}")
        gap = tangent_diff(m.qpos, current.qpos)
        damped = self.share + mu * np.eye(self.share.shape[1])
        extra = (1.0 + mu) * np.linalg.solve(damped, gap[..., None])[..., 0] - gap
        return m.with_(qpos=apply_step(m.qpos, extra))


def tracking_hessians(motion: RobotMotion, spec: ProblemSpec, weights: Weights) -> tuple[np.ndarray, np.ndarray]:
    """(T, nv, nv) Gauss-Newton Hessians of the tracked terms of the problem ``spec`` at every
    frame of ``motion``: the free-feet stage's (keypoints, limb directions, posture) and the pinned
    stage's (the same plus the corners of the soles planted in ``meta["contacts"]``, at their hard
    weight)."""
    from motion2robot.retarget.terms import contact_xy

    robot = spec.robot
    model, data = robot.model, robot.new_data()
    nv, L, T = model.nv, spec.length, motion.num_frames
    sites = np.asarray(robot.keypoint_sites)
    wk = np.asarray(robot.keypoint_weights, dtype=float) * weights.keypoint / L ** 2
    labels = motion.meta.get("contacts")
    planted = np.asarray(labels, dtype=bool) if np.shape(labels) == (T, 2) else np.zeros((T, 2), dtype=bool)
    soles = np.asarray(robot.sole_sites)
    hard = getattr(weights, contact_xy.TERM.name) / L ** 2
    free = np.zeros((T, nv, nv))
    pinned = np.zeros((T, nv, nv))
    jac = np.zeros((len(sites), 3, nv))
    corner = np.zeros((3, nv))
    eye3 = np.eye(3)
    for t in range(T):
        data.qpos[:] = motion.qpos[t]
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        for i, s in enumerate(sites):
            mujoco.mj_jacSite(model, data, jac[i], None, int(s))
        H = np.einsum("k,kai,kaj->ij", wk, jac, jac)
        x = data.site_xpos[sites]
        for a, b in spec.dir_pairs:
            v = x[b] - x[a]
            n = float(np.linalg.norm(v))
            u = v / n
            Jd = (eye3 - np.outer(u, u)) / n @ (jac[b] - jac[a])
            H += weights.direction * Jd.T @ Jd
        H[6:, 6:] += weights.posture * np.eye(nv - 6)
        free[t] = H
        for f in np.flatnonzero(planted[t]):
            for s in soles[f]:
                mujoco.mj_jacSite(model, data, corner, None, int(s))
                H = H + hard * corner.T @ corner
        pinned[t] = H
    return free, pinned


def attenuation(motion: RobotMotion, robot: Robot, options, tracked_legs: bool = True) -> Attenuation:
    """The :class:`Attenuation` of the whole-body retargeting with ``options`` (its weights at
    ``motion``'s rate, its iterations per stage) linearised at ``motion``. ``tracked_legs`` False
    (a ``steps`` result, whose root and legs the walking pattern lays rather than the solve):
    those coordinates pass as they are (G = I there)."""
    weights = rate_weights(options.weights, motion.fps)
    spec = build_spec(robot)
    free, pinned = tracking_hessians(motion, spec, weights)
    nv = free.shape[1]
    sv2 = np.ones(nv)
    sv2[:3] = 1.0 / spec.length ** 2  # the solver's scaling of the root translation
    D = np.diag((4.0 * weights.velocity + 16.0 * weights.acceleration) * sv2 + weights.damping)
    n_free, n_pinned = options.iterations
    left_free = np.linalg.matrix_power(np.linalg.solve(free + D, np.broadcast_to(D, free.shape)), n_free)
    left_pinned = np.linalg.matrix_power(np.linalg.solve(pinned + D, np.broadcast_to(D, pinned.shape)), n_pinned)
    share = np.eye(nv) - left_pinned @ left_free
    if not tracked_legs:
        laid = np.flatnonzero(np.concatenate([np.ones(6, dtype=bool), foot_ancestor_mask(robot).any(axis=1)]))
        share[:, laid, :] = 0.0
        share[:, :, laid] = 0.0
        share[:, laid, laid] = 1.0  # (i, i) for every laid coordinate i
    return Attenuation(motion, share)

"""The solver-driven stages of the whole-body pipeline, in the order they run.

1. :func:`free_solve`: every frame from the nominal posture with the soles only asked to touch the
   floor in contact frames (floor softened: continuation), then the exact velocity clamp;
2. :func:`pinned_solve`: again with every sole corner pinned to the contact plan's targets and the
   CoM over the shrunk support polygon (balance);
3. :func:`servo_rounds`: alternate smoothing the hinges (and, with balance, the root) to what the
   servos can follow (:mod:`~.smoothing`; rounded off, not clamped into a bang-bang) and a Newton
   projection onto the hard constraints, then the exact velocity clamp; up to REPAIR_ROUNDS more
   rounds while self-collision capsules still overlap;
4. :func:`joint_smoothing`: one filter for root and hinges together
   (:func:`~.smoothing.smooth_jointly`) and a low-pass at a fixed cutoff in Hz within the joint
   limits (:func:`~.smoothing.low_pass`: the same filter at any output rate) remove the solves'
   kinks and noise; a projection without the self-collision rows takes the pinned soles back,
   one with the legs held takes the arms and head out of the self-collisions the filter made
   (:func:`collision_pushes`), its pushes spread over neighbouring frames
   (:func:`~.smoothing.spread_correction`), and a last one over every joint takes what is left.

Each takes the :class:`~.setup.Setup` and returns the trajectory (T, nq).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from motion2robot.retarget.constraints import clamp_velocity
from motion2robot.retarget.contact_plan import ContactPlan, unpinned
from motion2robot.retarget.setup import Setup
from motion2robot.retarget.smoothing import (
    low_pass,
    smooth_hinges,
    smooth_jointly,
    smooth_to_targets,
    spread_correction,
)
from motion2robot.retarget.solver import EXTRA_TOLERANCE, correct, hinge_bounds
from motion2robot.retarget.targets import initial_qpos
from motion2robot.robot.chains import free_limbs

#: Factor on the floor weight in the first (free-feet) stage.
STAGE1_SOFTENING = 1e-3
#: Extra correction rounds at most, run while some self-collision capsule pair still overlaps by
#: more than REPAIR_TOLERANCE (m).
REPAIR_ROUNDS = 4
REPAIR_TOLERANCE = 0.001
#: Newton projection steps at most per round beyond the first two, on the frames still violating
#: a hard constraint (deep self-collisions need ~10).
EXTRA_CORRECTIONS = 8
#: Rounds of :func:`collision_pushes` and spreading in :func:`joint_smoothing` at most, run while a
#: capsule pair overlaps by more than PUSH_TOLERANCE (m); the last projection takes the rest.
PUSH_ROUNDS = 4
PUSH_TOLERANCE = 1e-5
#: Passes of :func:`collision_pushes` at most that project again the frames whose push turned
#: against the frame before's.
SIDE_PASSES = 6


def _clamp(setup: Setup, Q: np.ndarray) -> np.ndarray:
    Q[:, 7:] = clamp_velocity(Q[:, 7:], setup.robot.velocity_limit, setup.fps)
    return Q


def free_solve(setup: Setup) -> tuple[np.ndarray, object]:
    """Stage 1: the free-feet solve (and its stats); its velocity-clamped answer starts stage 2."""
    # the floor softened (continuation): a stiff floor from the first iteration traps frames whose
    # way from the nominal posture passes below it
    w1 = replace(setup.weights, floor=setup.weights.floor * STAGE1_SOFTENING)
    P1 = unpinned(setup).params(setup, balance=False)
    q0 = initial_qpos(setup.problem.spec, setup.kp)
    Q, stats = setup.solve(setup.problem, P1, q0, w1, setup.opt.iterations[0], setup.robot.lower, setup.robot.upper)
    return _clamp(setup, Q), stats


def pinned_solve(setup: Setup, plan: ContactPlan, Q: np.ndarray) -> tuple[np.ndarray, object]:
    """Stage 2: the solve with the contact plan's soles pinned and balance rows on."""
    return setup.solve(setup.problem, plan.params(setup), Q, setup.weights, setup.opt.iterations[1],
                       setup.robot.lower, setup.robot.upper)


def servo_rounds(setup: Setup, plan: ContactPlan, Q: np.ndarray) -> tuple[np.ndarray, int]:
    """Stage 3: the rounds of (smoothing within the servo's limits, projection, velocity clamp);
    returns the trajectory and the number of rounds run."""
    opt, robot = setup.opt, setup.robot
    lo, hi = robot.lower, robot.upper
    P = plan.params(setup)
    rounds = 0
    while rounds < opt.corrections + REPAIR_ROUNDS:
        # past opt.corrections, more rounds only while the capsules still overlap
        if rounds >= opt.corrections and (rounds == 0 or setup.points(Q)[3].min(initial=0.0) >= -REPAIR_TOLERANCE):
            break
        rounds += 1
        if opt.smoothing:
            Q[:, 7:] = smooth_hinges(Q[:, 7:], *setup.servo, setup.fps, robot.velocity_limit, lo, hi)
            if setup.root_target is not None:  # quasi-static: the root's acceleration would move the ZMP
                Q[:, :3] = smooth_to_targets(Q[:, :3], np.inf, setup.root_target, setup.fps)
        Q, _ = correct(setup.problem, P, Q, lo, hi, setup.max_step, 2, free_at_bounds=rounds > opt.corrections,
                       extra=EXTRA_CORRECTIONS)
        Q = _clamp(setup, Q)
    return Q, rounds


def smooth_configuration(setup: Setup, Q: np.ndarray) -> np.ndarray:
    """:func:`~motion2robot.retarget.smoothing.smooth_jointly` over root position, root quaternion
    (renormalised) and hinges, then the exact joint limits and velocity clamp."""
    robot = setup.robot
    v, a = setup.servo
    racc = setup.root_target if setup.root_target is not None else np.inf
    vt = np.concatenate([np.full(7, np.inf), v])
    at = np.concatenate([np.full(3, racc), np.full(4, np.inf), a])
    # the low-pass after the target smoothing: its weighted rows end in kinks in the columns that
    # did not need them (a walk-back's shoulder at 100 fps: 12 -> 25 rad/s^2; with it 15)
    # within the joint limits: a low-pass rounding a joint past its limit, clipped back, leaves a
    # kink (op3 throw samples at 100 fps: a shoulder at its limit 24 -> 44 rad/s^2)
    lo = np.concatenate([np.full(7, -np.inf), robot.lower])
    hi = np.concatenate([np.full(7, np.inf), robot.upper])
    out = low_pass(smooth_jointly(Q, vt, at, setup.fps), setup.fps, lower=lo, upper=hi)
    out[:, 3:7] /= np.linalg.norm(out[:, 3:7], axis=1, keepdims=True)
    out[:, 7:] = np.clip(clamp_velocity(out[:, 7:], robot.velocity_limit, setup.fps), robot.lower, robot.upper)
    return out


def collision_pushes(setup: Setup, P: np.ndarray, Q: np.ndarray, hit: np.ndarray) -> np.ndarray:
    """``Q`` (T, nq) with its frames ``hit`` (T,) taken out of self-collision by the free limbs
    alone (the legs held: the pinned soles would turn their push into a one-frame kink), each frame
    within a servo step of its neighbours. The projection's minimum-norm step picks its side per
    frame, and neighbouring frames of one grazing (an elbow at the thigh) took opposite sides (a
    shoulder pushed +0.2 and -0.2 rad in two consecutive frames), which no spreading of the pushes
    can smooth: a frame whose push turns against the push of the frame before is projected again
    from that push (up to SIDE_PASSES times)."""
    robot = setup.robot
    free = free_limbs(robot)
    q = Q[:, 7:]
    lo, hi = hinge_bounds(q, robot.lower, robot.upper, setup.max_step)
    lo = np.where(free, lo, q)   # legs: lower = upper = where they are
    hi = np.where(free, hi, q)
    out = Q.copy()
    rows = np.flatnonzero(hit)
    start = Q[rows].copy()
    after = hit.copy()
    after[0] = False
    after[1:] &= hit[:-1]                       # hit frames whose frame before is hit too
    for _ in range(SIDE_PASSES):
        if not len(rows):
            break
        b_lo = np.minimum(lo[rows], start[:, 7:])
        b_hi = np.maximum(hi[rows], start[:, 7:])
        out[rows], _ = correct(setup.problem, P[rows], start, b_lo, b_hi, None, 1, extra=EXTRA_CORRECTIONS)
        push = (out[:, 7:] - q) * free
        turned = np.zeros(len(Q), dtype=bool)
        turned[1:] = after[1:] & (np.sum(push[1:] * push[:-1], axis=1) < 0.0)
        rows = np.flatnonzero(turned)
        start = Q[rows].copy()
        start[:, 7:] = np.clip(q[rows] + push[rows - 1], robot.lower, robot.upper)
    return out


def free_limb_gaps(setup: Setup) -> np.ndarray:
    """(g,) bool: the self-collision gaps (``setup.points``' fourth output) some free-limb hinge
    moves, at the nominal posture: the collisions the arms and head can get out of."""
    robot = setup.robot
    q0 = np.asarray(robot.nominal_qpos, dtype=float)[None]
    free = np.flatnonzero(free_limbs(robot))
    Q = np.repeat(q0, len(free) + 1, axis=0)
    Q[np.arange(1, len(free) + 1), 7 + free] += 0.05
    Q[:, 7:] = np.clip(Q[:, 7:], robot.lower, robot.upper)
    g = setup.points(Q)[3]
    return (np.abs(g[1:] - g[0]) > 1e-9).any(axis=0)


def free_limbs_clear(setup: Setup, P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """``Q`` (T, nq) with the self-collisions the arms and head can get out of
    (:func:`free_limb_gaps`) taken out by them alone (:func:`collision_pushes`), each push spread
    over the neighbouring frames, up to PUSH_ROUNDS rounds; ``P``: the plan's parameters."""
    free = free_limbs(setup.robot)
    reach = free_limb_gaps(setup)   # a collision of the legs alone is left to the caller
    for _ in range(PUSH_ROUNDS):
        # a spread push is a different combination of the free limbs' joints than the frame's own
        # push, and can leave a little of the collision: the next round pushes and spreads that
        # (keeping a frame's own push there instead left a one-frame notch: 93 rad/s^2 at 100 fps)
        hit = setup.points(Q)[3][:, reach].min(axis=1, initial=0.0) < -PUSH_TOLERANCE
        if not hit.any():
            break
        pushed = collision_pushes(setup, P, Q, hit)
        pushed[:, 7:] = spread_correction(Q[:, 7:], pushed[:, 7:], free, setup.fps)
        Q = pushed
    return Q


def joint_smoothing(setup: Setup, plan: ContactPlan, Q: np.ndarray) -> np.ndarray:
    """Stage 4: the joint filter, then the projection back onto the hard constraints in three
    steps. The pinned soles back with every joint, without the self-collision rows (to second
    order of what the filter moved). In the frames the filter left in a self-collision that the
    arms or head can get out of (:func:`free_limb_gaps`), the free limbs alone take the body out
    (:func:`collision_pushes`), their pushes spread over neighbouring frames. Last, every joint on
    the frames still off a hard constraint (a collision of the legs alone, the CoM the arms moved).
    Left to the legs, a collision push is a one-frame kink that nothing smooths after this stage
    (op3 throw at 100 fps: an elbow grazing the thigh, 553 rad/s^2 in a hip and 23 m/s^2 at the
    root)."""
    robot = setup.robot
    P = plan.params(setup)
    Q = smooth_configuration(setup, Q)
    # the soles back first, with every joint but without the self-collision rows: a frame whose
    # legs are held below would otherwise put its soles back by the root alone, unlike its
    # neighbours (G1 throw at 100 fps: a 0.07 mm root step, 0.9 m/s^2)
    Q, _ = correct(setup.problem, P, Q, robot.lower, robot.upper, setup.max_step, 1, extra=EXTRA_CORRECTIONS,
                   collisions=False)
    Q = free_limbs_clear(setup, P, Q)
    # every joint, on the frames still off a hard constraint (the arms' pushes moved the CoM, a
    # collision the arms could not resolve)
    v = setup.problem.violation_eval(len(Q))(Q, P)[0][:, 0]
    rows = np.flatnonzero(v > EXTRA_TOLERANCE)
    if len(rows):
        lo, hi = hinge_bounds(Q[:, 7:], robot.lower, robot.upper, setup.max_step)
        Q[rows], _ = correct(setup.problem, P[rows], Q[rows], lo[rows], hi[rows], None, 1, extra=EXTRA_CORRECTIONS)
    Q[:, 7:] = np.clip(clamp_velocity(Q[:, 7:], robot.velocity_limit, setup.fps), robot.lower, robot.upper)
    return Q

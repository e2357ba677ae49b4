"""``retarget(human, robot, options) -> RobotMotion``: the whole pipeline in memory.

1. scale the human keypoints to the robot (:mod:`~motion2robot.retarget.scale`);
2. solve every frame (batched LM, :mod:`~motion2robot.retarget.solver`; every step followed by a
   Newton projection onto the contact/floor/balance rows) with the soles only asked to touch the
   floor in contact frames; clamp joint velocities;
3. pin each contact phase's sole where step 2 put it when the phase began
   (:mod:`~motion2robot.retarget.contacts`), moving a phase that begins while the other foot is
   pinned out of that foot's capsule (:mod:`~motion2robot.retarget.anchor_gap`) and, with balance
   on, build the shrunk support polygons; solve again from step 2's answer;
4. twice: smooth the hinge trajectories where their speed or acceleration exceed what the servo
   can do (:mod:`~motion2robot.retarget.smoothing`; rounded off instead of clamped into a
   bang-bang), Newton projection onto the hard constraints (contact, floor, balance,
   self-collision; each frame's hinges within the velocity limit of its neighbours), then the exact
   joint-velocity clamp (:mod:`~motion2robot.retarget.constraints`); up to REPAIR_ROUNDS more
   such rounds while self-collision capsules still overlap (hinges at a velocity bound then free
   to take part in the projection step);
5. exact root pass (:mod:`~motion2robot.retarget.root_pass`): rotate the root about the vertical
   and translate it so no sole corner is below the floor and the stance sole neither slides nor
   spins (joint angles untouched);
6. per-frame figures (keypoint error, constraint residuals) into ``meta["solver"]``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from motion2robot.errors import SolverError
from motion2robot.motion.human import KP, SMPL22, HumanMotion
from motion2robot.motion.ops import resample
from motion2robot.retarget import native
from motion2robot.retarget.anchor_gap import foot_capsules, separate_anchors
from motion2robot.retarget.collision import MARGIN
from motion2robot.retarget.compiled import CompiledProblem, compiled_problem
from motion2robot.retarget.constraints import (
    MARGIN_FRACTION,
    clamp_velocity,
    support_margin,
    support_planes,
)
from motion2robot.retarget.contacts import anchor_soles, contact_labels, planted
from motion2robot.retarget.costs import FRAME_TERMS, Weights
from motion2robot.retarget.finite import check_solution, check_targets
from motion2robot.retarget.problem import HMAX
from motion2robot.retarget.root_pass import root_shift
from motion2robot.retarget.scale import Scale, auto_scale, scaled_keypoints
from motion2robot.retarget.smoothing import root_acceleration_target, servo_targets, smooth_hinges, smooth_to_targets
from motion2robot.retarget.solver import correct, objective
from motion2robot.retarget.targets import frame_params, initial_qpos
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion

#: Factor on the floor weight in the first (free-feet) stage.
STAGE1_SOFTENING = 1e-3
#: m of clearance kept between the feet's capsules (besides the collision MARGIN) when anchoring.
ANCHOR_CLEARANCE = 0.002
#: Extra correction rounds at most, run while some self-collision capsule pair still overlaps by
#: more than REPAIR_TOLERANCE (m).
REPAIR_ROUNDS = 4
REPAIR_TOLERANCE = 0.001
#: Newton projection steps at most per round beyond the first two, on the frames still violating
#: a hard constraint (deep self-collisions need ~10).
EXTRA_CORRECTIONS = 8


@dataclass(frozen=True)
class RetargetOptions:
    """balance: keep the CoM over the shrunk support polygon (quasi-static motions; turn off for
    running/jumping). fps: resample the human motion first (None = keep its rate).
    scale: force a Scale (None = automatic, with the robot config's overrides).
    contacts: use foot contact constraints (off = free feet, only the floor; for tests).
    iterations: LM iterations of the free-feet and pinned stages; corrections: rounds of (smoothing
    within the servo's speed/acceleration + 2 Newton projections onto the hard constraints + the
    exact velocity clamp). margin: support polygon
    shrink (m; None = a quarter of the smaller sole half-extent). backend: "auto" | "lanes" | "c" | "vm" (see :mod:`~motion2robot.retarget.compiled`).
    solver: "fast" (batched LM, :mod:`~motion2robot.retarget.solver`) or "ipopt" (the per-frame
    baseline of :mod:`~motion2robot.retarget.baseline`, same costs). smoothing: round off the
    hinge trajectories to the speed/acceleration the servos can follow
    (:func:`~motion2robot.retarget.smoothing.servo_targets`) and, with balance on, the root's
    acceleration (off = only the exact velocity clamp; faster motion, may fail the torque checks).
    root_pass: finish with the exact root pass (a translation of the root only: floor, stance
    sole pinned). hold_stance_yaw: the root pass also turns the whole robot about the vertical so a
    foot alone in contact keeps its yaw (no spinning stance foot). Off by default: it stops the
    spin, but turns the body off the human's heading (walk: heading error 2 -> 11 deg, path error
    3 -> 20 cm) and its easing back makes both feet slide a little in some double-support frames
    of quasi-static clips (bandai byebye, an MDM throw), which then fail the ground check."""

    balance: bool = True
    fps: float | None = None
    scale: Scale | None = None
    contacts: bool = True
    weights: Weights = field(default_factory=Weights)
    iterations: tuple[int, int] = (3, 3)
    corrections: int = 2
    margin: float | None = None
    backend: str = "auto"
    solver: str = "fast"
    smoothing: bool = True
    root_pass: bool = True
    hold_stance_yaw: bool = False


def _points(problem: CompiledProblem, Q: np.ndarray) -> tuple[np.ndarray, ...]:
    T = len(Q)
    kp, corners, com, gaps = problem.points_eval(T)(Q)
    return kp.reshape(T, -1, 3), corners.reshape(T, 2, 4, 3), com.reshape(T, 3), gaps.reshape(T, -1)


def _residuals(problem: CompiledProblem, pts: tuple[np.ndarray, ...], kp: np.ndarray, labels: np.ndarray,
               soles: np.ndarray | None, planes: np.ndarray, balanced: np.ndarray) -> dict:
    """Per-frame mean keypoint error (m) and constraint residuals (m: sole depth, contact z/slip,
    CoM outside the shrunk polygon, capsule penetration), measured on the final trajectory, whose
    :func:`_points` are ``pts``."""
    kp_r, corners, com, gaps = pts
    T = len(kp_r)
    err = np.linalg.norm(kp_r - kp[:, [KP[k] for k in problem.spec.kp_names]], axis=-1).mean(axis=1)
    floor = np.maximum(0.0, -corners[..., 2].min(axis=(1, 2)))
    contact = np.zeros(T)
    if soles is not None:
        dz = np.abs(corners[..., 2]).max(axis=-1)                                   # (T, 2)
        dxy = np.linalg.norm(corners[..., :2].mean(axis=2) - np.nan_to_num(soles)[..., :2].mean(axis=2), axis=-1)
        contact = np.where(labels, np.maximum(dz, dxy), 0.0).max(axis=1)
    balance = np.where(balanced, np.maximum(0.0, -support_margin(com[:, :2], planes)), 0.0)
    coll = np.maximum(0.0, -gaps.min(axis=1)) if gaps.shape[1] else np.zeros(T)
    violation = np.maximum.reduce([floor, contact, balance, coll])
    return {
        "residual_per_frame": err.tolist(), "max_residual": float(err.max()),
        "constraint_residual_per_frame": violation.tolist(), "max_constraint_residual": float(violation.max()),
        "max_constraint_residuals": {"floor": float(floor.max()), "contact": float(contact.max()),
                                     "balance": float(balance.max()), "self_collision": float(coll.max())},
    }


def retarget(human: HumanMotion, robot: Robot, options: RetargetOptions | None = None) -> RobotMotion:
    """Retarget a canonical human motion onto ``robot``; the result's meta carries the scale,
    the contacts used, the scaled human root path and the solver's figures."""
    opt = options or RetargetOptions()
    if opt.fps is not None and abs(opt.fps - human.fps) > 1e-9:
        human = resample(human, opt.fps)
    T = human.num_frames
    where = human.meta.get("source", "the motion")
    if T < 2:
        raise SolverError(f"{where}: the clip has {T} frame; retargeting needs at least 2 frames (velocity limits, contacts)")
    if not np.all(np.isfinite(human.positions)):
        raise SolverError(f"{where}: keypoints contain NaN/inf; fix or trim the clip")
    t_all = time.perf_counter()
    problem = compiled_problem(robot, opt.backend)
    native.library()  # the smoothing/clamp kernels: built on first use, like the problem's code
    spec, w = problem.spec, opt.weights
    scale = opt.scale or auto_scale(human, robot)
    kp = scaled_keypoints(human.positions, scale)
    check_targets(kp, SMPL22, where)
    if opt.contacts:
        labels, label_source = contact_labels(human)
        heel_up = int(labels.sum())
        labels = planted(labels, human)
        heel_up -= int(labels.sum())
    else:
        heel_up = 0
        labels, label_source = np.zeros((T, 2), dtype=bool), "off"
    lo, hi = robot.lower, robot.upper
    if opt.solver not in ("fast", "ipopt"):
        raise SolverError(f"unknown solver {opt.solver!r}; use 'fast' or 'ipopt'")
    if opt.solver == "ipopt":
        from motion2robot.retarget.baseline import solve_ipopt as solve
    else:
        from motion2robot.retarget.solver import solve
    t_solve = time.perf_counter()
    q0 = initial_qpos(spec, kp)
    P1 = frame_params(spec, kp, labels, None, None, None)
    # stage 1 with the floor softened (continuation): a stiff floor from the first iteration
    # traps frames whose way from the nominal posture passes below it
    w1 = replace(w, floor=w.floor * STAGE1_SOFTENING)
    Q, st1 = solve(problem, P1, q0, w1, opt.iterations[0], lo, hi)
    max_step = robot.velocity_limit / human.fps
    Q[:, 7:] = clamp_velocity(Q[:, 7:], robot.velocity_limit, human.fps)  # feasible start for stage 2
    _, corners, _, _ = _points(problem, Q)
    soles = anchor_soles(corners, labels) if opt.contacts else None
    feet = foot_capsules(robot) if opt.contacts else None
    anchor_push = 0.0
    if feet is not None:  # phases anchored at different frames must not pin the feet into each other
        soles, anchor_push = separate_anchors(soles, labels, *feet, MARGIN + ANCHOR_CLEARANCE)
    half = min(min(f.sole_half) for f in robot.config.feet)
    margin = opt.margin if opt.margin is not None else MARGIN_FRACTION * half
    planes = np.tile([0.0, 0.0, 1.0], (T, HMAX, 1))
    support = labels.any(axis=1)
    if opt.contacts:
        planes, support = support_planes(soles, labels, margin)
    P2 = frame_params(spec, kp, labels, soles, planes, support if opt.balance else None)
    Q, st2 = solve(problem, P2, Q, w, opt.iterations[1], lo, hi)
    targets = servo_targets(robot)
    root_target = root_acceleration_target(robot) if opt.balance else None
    rounds, pts = 0, None  # pts: _points of the current Q, when known
    while rounds < opt.corrections + REPAIR_ROUNDS:  # alternate: smooth within the servo's limits, then the hard constraints
        # past opt.corrections, more rounds only while the capsules still overlap
        if rounds >= opt.corrections:
            pts = _points(problem, Q) if rounds else None
            if pts is None or pts[3].min(initial=0.0) >= -REPAIR_TOLERANCE:
                break
        rounds, pts = rounds + 1, None
        if opt.smoothing:
            Q[:, 7:] = smooth_hinges(Q[:, 7:], *targets, human.fps, robot.velocity_limit, lo, hi)
            if root_target is not None:  # quasi-static: the root's acceleration would move the ZMP
                Q[:, :3] = smooth_to_targets(Q[:, :3], np.inf, root_target, human.fps)
        Q, _ = correct(problem, P2, Q, lo, hi, max_step, 2, free_at_bounds=rounds > opt.corrections,
                       extra=EXTRA_CORRECTIONS)
        Q[:, 7:] = clamp_velocity(Q[:, 7:], robot.velocity_limit, human.fps)
    pts = pts or _points(problem, Q)
    shift = None
    if opt.root_pass:  # joints final: move only the root onto the floor / stance anchors
        shift = root_shift(pts[1], labels, human.fps, root_target if opt.smoothing else None,
                           hold_yaw=opt.hold_stance_yaw)
        Q = shift.apply(Q)  # a rigid root motion moves every point with it; the capsule gaps stay
        pts = (shift.points(pts[0]), shift.points(pts[1]), shift.points(pts[2][:, None])[:, 0], pts[3])
    solve_s = time.perf_counter() - t_solve
    check_solution(Q, robot.joint_names, where)

    terms, temporal = objective(problem, P2, Q, w)  # the final trajectory's objective (stage 2's)
    # contact residual against each phase's placement in its first frame of the final trajectory
    # (the root pass keeps the stance sole there, not at the solver's anchors)
    final_soles = anchor_soles(pts[1], labels) if opt.contacts else None
    if final_soles is not None and opt.balance and shift is not None:
        planes = support_planes(final_soles, labels, margin)[0]
    figures = _residuals(problem, pts, kp, labels, final_soles, planes, support & opt.balance & opt.contacts)
    total_s = time.perf_counter() - t_all
    meta = {
        "source": human.meta.get("source"), "clip": human.meta.get("clip"), "prompt": human.meta.get("prompt"),
        "format": human.meta.get("format"), "scale": scale.as_dict(), "robot_hash": robot.model_hash,
        "contacts": labels.astype(int).tolist(), "contacts_source": label_source,
        "contact_frames_heel_up": heel_up,
        "human_root_xy": kp[:, 0, :2].tolist(), "balance": bool(opt.balance), "support_margin": margin,
        "solver": {
            "method": ("batched Gauss-Newton/LM (" + problem.backend + " backend)" if opt.solver == "fast"
                       else "per-frame IPOPT (casadi nlpsol)"),
            "time_s": solve_s, "total_s": total_s, "frames_per_s": T / solve_s if solve_s > 0 else None,
            "compile_s": problem.compile_s, "build_s": problem.build_s, "compiled_from_cache": problem.cached,
            "iterations": [st1.iterations, st2.iterations], "correction_rounds": rounds, **figures,
            "objective": {"total": float(terms.sum() + temporal.sum()), "temporal": float(temporal.sum()),
                          **dict(zip(FRAME_TERMS, terms.sum(axis=0).tolist()))},
            "weights": w.as_dict(),
            "anchor_push_m": anchor_push,
            "root_pass": shift.figures() if shift is not None else None,
            "smoothing": ({"speed_target_rad_s": targets[0].tolist(), "acceleration_target_rad_s2": targets[1].tolist(),
                           "root_acceleration_target_m_s2": root_target} if opt.smoothing else None),
        },
    }
    return RobotMotion(qpos=Q, fps=human.fps, joint_names=robot.joint_names, robot=robot.name, meta=meta)

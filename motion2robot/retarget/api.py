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
5. one smoothing filter for root and hinges together (:func:`~.smoothing.smooth_jointly`), a
   projection back onto the hard constraints, its pushes on free limbs spread over neighbouring
   frames (:func:`~.smoothing.spread_correction`);
6. dynamic balance (:mod:`~motion2robot.retarget.zmp_plan`): the ZMP brought inside the soles by a
   planned CoM path the trajectory is projected onto (kept only where it helps);
7. exact root pass (:mod:`~motion2robot.retarget.root_pass`): rotate the root about the vertical
   and translate it so no sole corner is below the floor and the stance sole neither slides nor
   spins (joint angles untouched);
8. per-frame figures (keypoint error, constraint residuals) into ``meta["solver"]``.

Steps 1-8 are :func:`whole_body`. :func:`retarget` wraps them in the tempo and legs policy of
:mod:`~motion2robot.retarget.executable` (attempts judged by ``check``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from motion2robot.errors import SolverError, UserError
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
from motion2robot.retarget.executable import plan
from motion2robot.retarget.root_pass import root_shift
from motion2robot.retarget.scale import Scale, auto_scale, scaled_keypoints
from motion2robot.retarget.smoothing import (
    root_acceleration_target,
    servo_targets,
    smooth_hinges,
    smooth_jointly,
    smooth_to_targets,
    spread_correction,
)
from motion2robot.retarget.solver import EXTRA_TOLERANCE, correct, objective
from motion2robot.retarget.targets import frame_params, initial_qpos
from motion2robot.retarget.tempo import DEFAULT_CAP, parse_cap, parse_tempo
from motion2robot.retarget.zmp_plan import MIN_SHIFT, cart_table_shift, com_boxes, multibody_zmp
from motion2robot.robot.chains import free_limbs
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion

#: fps at which the temporal weights apply as given (see ``_rate_weights``).
TEMPORAL_REFERENCE_FPS = 20.0
#: Rounds of the ZMP planning stage at most.
ZMP_ROUNDS = 2
#: The ZMP planning stage is tried when the ZMP leaves the soles by at most this many sole lengths.
ZMP_REACH = 2.0
#: What ``legs`` may be.
LEGS = ("auto", "whole", "stance")
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
    of quasi-static clips (bandai byebye, an MDM throw), which then fail the ground check.
    dynamic_balance: with balance, a ZMP planning stage after the whole-body solve keeps the
    multi-body ZMP inside the shrunk support polygons (:mod:`~motion2robot.retarget.zmp_plan`).
    tempo: "human" | "similar" | "auto" | a slow-down factor (:mod:`~motion2robot.retarget.tempo`);
    tempo_cap: the slowest ``auto`` may go; legs: "whole" | "stance" | "auto" (whole body, the
    stance alternative of :mod:`~motion2robot.retarget.stance`, or whole body unless only the
    stance passes); with "auto" in either, the result is judged by ``check`` and the policy of
    :mod:`~motion2robot.retarget.executable` picks the attempt."""

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
    dynamic_balance: bool = True
    tempo: str | float = "auto"
    tempo_cap: float = DEFAULT_CAP
    legs: str = "auto"

    def __post_init__(self) -> None:
        object.__setattr__(self, "tempo", parse_tempo(self.tempo))
        object.__setattr__(self, "tempo_cap", parse_cap(self.tempo_cap))
        if self.legs not in LEGS:
            raise UserError(f"--legs {self.legs!r}: choose one of {', '.join(LEGS)}")


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
        dxy = np.linalg.norm(corners[..., :2] - np.nan_to_num(soles)[..., :2], axis=-1).max(axis=-1)  # (T, 2)
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


def _rate_weights(w: Weights, fps: float) -> Weights:
    """The temporal weights act on per-frame differences, which shrink as the rate grows: scaled by
    (fps / TEMPORAL_REFERENCE_FPS)^2 so a finer output rate does not loosen them (at 100 fps
    unscaled, a byebye's peak joint acceleration grew 1.6x over the native 30 fps; scaled, 0.6x)."""
    k = (fps / TEMPORAL_REFERENCE_FPS) ** 2
    return replace(w, velocity=w.velocity * k, acceleration=w.acceleration * k)


def _require_solvable(human: HumanMotion) -> None:
    """SolverError (a user error) for clips no stage can retarget."""
    where = human.meta.get("source", "the motion")
    if human.num_frames < 2:
        raise SolverError(f"{where}: the clip has {human.num_frames} frame; retargeting needs at least 2 frames "
                          "(velocity limits, contacts)")
    if not np.all(np.isfinite(human.positions)):
        raise SolverError(f"{where}: keypoints contain NaN/inf; fix or trim the clip")


def _smooth_configuration(Q: np.ndarray, robot: Robot, fps: float, targets: tuple[np.ndarray, np.ndarray],
                          root_target: float | None) -> np.ndarray:
    """:func:`~motion2robot.retarget.smoothing.smooth_jointly` over root position, root quaternion
    (renormalised) and hinges, then the exact joint limits and velocity clamp."""
    v, a = targets
    racc = root_target if root_target is not None else np.inf
    vt = np.concatenate([np.full(7, np.inf), v])
    at = np.concatenate([np.full(3, racc), np.full(4, np.inf), a])
    out = smooth_jointly(Q, vt, at, fps)
    out[:, 3:7] /= np.linalg.norm(out[:, 3:7], axis=1, keepdims=True)
    out[:, 7:] = np.clip(clamp_velocity(out[:, 7:], robot.velocity_limit, fps), robot.lower, robot.upper)
    return out


def _dynamic_balance(problem: CompiledProblem, kp: np.ndarray, labels: np.ndarray, soles: np.ndarray,
                     planes: np.ndarray, support: np.ndarray, Q: np.ndarray, robot: Robot, fps: float,
                     max_step: np.ndarray) -> tuple[np.ndarray, dict]:
    """The ZMP planning stage (:mod:`~motion2robot.retarget.zmp_plan`): up to ZMP_ROUNDS rounds of
    (measure the multi-body ZMP, plan a CoM shift by the cart-table QP, pin the CoM to the
    shifted path and project the trajectory onto it and the other hard constraints). Kept only if
    it brings the ZMP closer to the soles without leaving any hard constraint (contacts, floor,
    self-collision) violated; otherwise the trajectory is returned as it came (``applied`` False)."""
    def outside(zmp: np.ndarray) -> float:
        return float(np.max(np.maximum(0.0, -support_margin(np.nan_to_num(zmp), planes)) * support, initial=0.0))

    figures = {"applied": False, "rounds": 0, "max_shift_m": 0.0}
    Q0 = Q
    zmp, com = multibody_zmp(Q, fps, robot)
    figures["zmp_outside_before_m"] = before = outside(zmp)
    reach = ZMP_REACH * 2.0 * max(max(f.sole_half) for f in robot.config.feet)
    if before > reach:  # spikes of a motion this fast are not a CoM shift away: not worth the rounds
        figures["zmp_outside_after_m"] = before
        figures["skipped"] = f"the ZMP is {before:.2f} m outside the soles, beyond {reach:.2f} m"
        return Q, figures
    for _ in range(ZMP_ROUNDS):
        d, _ = cart_table_shift(zmp, com[:, 2], planes, support, fps)
        if np.abs(d).max() < MIN_SHIFT:
            break
        boxes = com_boxes(com[:, :2] + d, support, planes)
        P3 = frame_params(problem.spec, kp, labels, soles, boxes, support)
        Q, _ = correct(problem, P3, Q, robot.lower, robot.upper, max_step, 2, extra=EXTRA_CORRECTIONS)
        Q[:, 7:] = clamp_velocity(Q[:, 7:], robot.velocity_limit, fps)
        figures["rounds"] += 1
        figures["max_shift_m"] = max(figures["max_shift_m"], float(np.abs(d).max()))
        zmp, com = multibody_zmp(Q, fps, robot)
    figures["zmp_outside_after_m"] = after = outside(zmp)
    if figures["rounds"] and after < before:  # the other hard rows (no CoM boxes) must hold as before
        P_plain = frame_params(problem.spec, kp, labels, soles, planes, None)
        if float(np.max(problem.violation_eval(len(Q))(Q, P_plain)[0], initial=0.0)) <= EXTRA_TOLERANCE:
            figures["applied"] = True
            return Q, figures
    figures["zmp_outside_after_m"] = before
    return Q0, figures


def retarget(human: HumanMotion, robot: Robot, options: RetargetOptions | None = None) -> RobotMotion:
    """Retarget a canonical human motion onto ``robot`` at the tempo and with the legs the options
    ask for (by default the first that passes ``check``: see
    :mod:`~motion2robot.retarget.executable`); the result's meta carries the scale, the contacts
    used, the scaled human root path, the solver's figures, the tempo and the fallback taken."""
    return retarget_and_check(human, robot, options)[0]


def retarget_and_check(human: HumanMotion, robot: Robot, options: RetargetOptions | None = None,
                       check_options: object | None = None) -> tuple[RobotMotion, object | None]:
    """:func:`retarget`, also returning the ``check`` report of the chosen attempt (None when the
    policy judged nothing: fixed tempo and legs); ``check_options`` are the judge's."""
    opt = options or RetargetOptions()
    if opt.fps is not None and abs(opt.fps - human.fps) > 1e-9:
        human = resample(human, opt.fps)
    _require_solvable(human)
    inner = replace(opt, fps=None)
    return plan(human, robot, opt.tempo, opt.legs, opt.tempo_cap, lambda h: whole_body(h, robot, inner), check_options)


def whole_body(human: HumanMotion, robot: Robot, options: RetargetOptions | None = None) -> RobotMotion:
    """The whole-body kinematic pipeline (steps 1-6 of the module text) on ``human`` as given."""
    opt = options or RetargetOptions()
    if opt.fps is not None and abs(opt.fps - human.fps) > 1e-9:
        human = resample(human, opt.fps)
    T = human.num_frames
    where = human.meta.get("source", "the motion")
    _require_solvable(human)
    where = human.meta.get("source", "the motion")
    t_all = time.perf_counter()
    problem = compiled_problem(robot, opt.backend)
    native.library()  # the smoothing/clamp kernels: built on first use, like the problem's code
    spec, w = problem.spec, _rate_weights(opt.weights, human.fps)
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
    if opt.smoothing:  # one filter for root and hinges together removes the solves' kinks; a last
        # projection takes the planted soles back where the filter moved them (to second order)
        Q = _smooth_configuration(Q, robot, human.fps, targets, root_target)
        smooth = Q
        Q, _ = correct(problem, P2, Q, lo, hi, max_step, 1, extra=EXTRA_CORRECTIONS)
        # the projection's pushes on free limbs (self-collision) spread over neighbouring frames
        Q[:, 7:] = spread_correction(smooth[:, 7:], Q[:, 7:], free_limbs(robot), human.fps)
        Q[:, 7:] = np.clip(clamp_velocity(Q[:, 7:], robot.velocity_limit, human.fps), lo, hi)
        pts = None
    zmp_figures = None
    if opt.balance and opt.dynamic_balance and opt.contacts:  # the ZMP, not only the CoM, inside the soles
        Q, zmp_figures = _dynamic_balance(problem, kp, labels, soles, planes, support, Q, robot, human.fps, max_step)
        pts = None
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
            "dynamic_balance": zmp_figures,
            "root_pass": shift.figures() if shift is not None else None,
            "smoothing": ({"speed_target_rad_s": targets[0].tolist(), "acceleration_target_rad_s2": targets[1].tolist(),
                           "root_acceleration_target_m_s2": root_target} if opt.smoothing else None),
        },
    }
    return RobotMotion(qpos=Q, fps=human.fps, joint_names=robot.joint_names, robot=robot.name, meta=meta)

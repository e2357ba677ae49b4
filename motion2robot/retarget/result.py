"""The whole-body pipeline's result: the robot motion and the figures its meta carries
(keypoint error and constraint residuals per frame, the objective, each stage's figures).

Units: metres, radians, seconds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2robot.motion.human import KP
from motion2robot.retarget.constraints import support_margin, support_planes
from motion2robot.retarget.contact_plan import ContactPlan
from motion2robot.retarget.contacts import anchor_soles
from motion2robot.retarget.costs import FRAME_TERMS
from motion2robot.retarget.setup import Setup
from motion2robot.retarget.solver import objective
from motion2robot.robot_motion import RobotMotion


def residuals(setup: Setup, pts: tuple[np.ndarray, ...], labels: np.ndarray, soles: np.ndarray | None,
              planes: np.ndarray, balanced: np.ndarray) -> dict:
    """Per-frame mean keypoint error (m) and constraint residuals (m: sole depth, contact z/slip,
    CoM outside the shrunk polygon, capsule penetration), measured on the final trajectory, whose
    :meth:`~.setup.Setup.points` are ``pts``."""
    kp_r, corners, com, gaps = pts
    T = len(kp_r)
    err = np.linalg.norm(kp_r - setup.kp[:, [KP[k] for k in setup.problem.spec.kp_names]], axis=-1).mean(axis=1)
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


@dataclass(frozen=True)
class StageFigures:
    """What the stages report: solver stats of stages 1 and 2 (``pinned`` None when the pipeline
    has no pinned solve, as ``steps``), correction rounds, the dynamic balance and root pass
    figures (None when not run), times (s)."""

    free: object
    pinned: object | None
    rounds: int
    dynamic_balance: dict | None
    root_pass: dict | None
    solve_s: float
    total_s: float


def robot_motion(setup: Setup, plan: ContactPlan, Q: np.ndarray, pts: tuple[np.ndarray, ...],
                 stages: StageFigures, root_passed: bool) -> RobotMotion:
    """The RobotMotion of the final trajectory ``Q`` (whose points are ``pts``) with its meta."""
    opt, human, problem = setup.opt, setup.human, setup.problem
    T = len(Q)
    terms, temporal = objective(problem, plan.params(setup), Q, setup.weights)  # stage 2's objective
    # contact residual against each phase's placement in its first frame of the final trajectory
    # (the root pass keeps the stance sole there, not at the solver's anchors)
    labels, planes = plan.labels, plan.planes
    final_soles = anchor_soles(pts[1], labels) if opt.contacts else None
    if final_soles is not None and opt.balance and root_passed:
        planes = support_planes(final_soles, labels, plan.margin)[0]
    figures = residuals(setup, pts, labels, final_soles, planes, plan.support & opt.balance & opt.contacts)
    solve_s = stages.solve_s
    meta = {
        "source": human.meta.get("source"), "clip": human.meta.get("clip"), "prompt": human.meta.get("prompt"),
        "format": human.meta.get("format"), "scale": setup.scale.as_dict(), "robot_hash": setup.robot.model_hash,
        "contacts": labels.astype(int).tolist(), "contacts_source": setup.label_source,
        "contact_frames_heel_up": setup.heel_up,
        "human_root_xy": setup.kp[:, 0, :2].tolist(), "balance": bool(opt.balance), "support_margin": plan.margin,
        "solver": {
            "method": ("batched Gauss-Newton/LM (" + problem.backend + " backend)" if opt.solver == "fast"
                       else "per-frame IPOPT (casadi nlpsol)"),
            "time_s": solve_s, "total_s": stages.total_s, "frames_per_s": T / solve_s if solve_s > 0 else None,
            "compile_s": problem.compile_s, "build_s": problem.build_s, "compiled_from_cache": problem.cached,
            "iterations": [stages.free.iterations, stages.pinned.iterations if stages.pinned is not None else 0], "correction_rounds": stages.rounds,
            **figures,
            "objective": {"total": float(terms.sum() + temporal.sum()), "temporal": float(temporal.sum()),
                          **dict(zip(FRAME_TERMS, terms.sum(axis=0).tolist()))},
            "weights": setup.weights.as_dict(),
            "anchor_push_m": plan.anchor_push,
            "feet": plan.feet.figures() if plan.feet is not None else None,
            "dynamic_balance": stages.dynamic_balance,
            "root_pass": stages.root_pass,
            "smoothing": ({"speed_target_rad_s": setup.servo[0].tolist(),
                           "acceleration_target_rad_s2": setup.servo[1].tolist(),
                           "root_acceleration_target_m_s2": setup.root_target} if opt.smoothing else None),
        },
    }
    return RobotMotion(qpos=Q, fps=human.fps, joint_names=setup.robot.joint_names, robot=setup.robot.name, meta=meta)


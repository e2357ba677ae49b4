"""The retargeting acceptance figures of one result, measured with MuJoCo on the robot's own
geometry (not with the solver's model): joint-limit violations, worst sole depth, share of
contact frames whose sole centre moves at most 1 cm/s, worst self-collision depth (MuJoCo geoms,
the validator's pair rules), joint speed / limit, CoM inside the shrunk support polygon, and the
smoothness figures: velocity sign reversals above 1 rad/s and the peak joint acceleration."""

from __future__ import annotations

import mujoco
import numpy as np

from motion2robot.retarget.constraints import MARGIN_FRACTION, convex_hull, halfplanes
from motion2robot.robot.poses import frame_poses
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion

SLIDE_SPEED = 0.01  # m/s
REVERSAL_SPEED = 1.0  # rad/s


def velocity_reversals(hinge: np.ndarray, fps: float, speed: float = REVERSAL_SPEED) -> int:
    """Number of (joint, frame) pairs where the joint speed changes sign between consecutive
    frames while above ``speed`` (rad/s) on both sides: a frame-to-frame zigzag."""
    v = np.diff(hinge, axis=0) * fps
    return int(np.sum((v[1:] * v[:-1] < 0) & (np.abs(v[1:]) > speed) & (np.abs(v[:-1]) > speed)))


def peak_acceleration(hinge: np.ndarray, fps: float) -> float:
    """Largest |second difference| * fps^2 of the (T, n) hinge angles (rad/s^2)."""
    return float(np.abs(np.diff(hinge, 2, axis=0)).max() * fps * fps) if len(hinge) > 2 else 0.0


def _self_collision_depth(robot: Robot, qpos: np.ndarray) -> np.ndarray:
    """(T,) deepest robot-robot penetration per frame (m) as the validator judges it: geom pairs
    MuJoCo tests, beyond their overlap at the nominal posture."""
    from motion2robot.validate.collision import pair_table
    from motion2robot.validate.models import check_model

    m = check_model(robot)
    d = mujoco.MjData(m)
    table = pair_table(robot)
    out = np.zeros(len(qpos))
    for t, q in enumerate(qpos):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_collision(m, d)
        if d.ncon:
            con = d.contact[:d.ncon]
            excess = table.excess(con.geom[:, 0], con.geom[:, 1], con.dist)
            out[t] = max(0.0, float(excess.max()))
    return out


def acceptance(motion: RobotMotion, robot: Robot, collisions: bool = True) -> dict:
    """Figures of ``motion`` (made by :func:`~motion2robot.retarget.retarget`, whose meta holds the
    contact labels) on ``robot``."""
    q = motion.qpos
    T = len(q)
    hinge = q[:, 7:]
    tol = 1e-9
    limit_viol = int(np.sum(hinge < robot.lower - tol) + np.sum(hinge > robot.upper + tol))
    vel = np.abs(np.diff(hinge, axis=0)) * motion.fps
    speed_ratio = float((vel / robot.velocity_limit).max()) if T > 1 else 0.0
    poses = frame_poses(robot.model, q, robot.sole_sites.ravel(), com_body=robot.root_body)
    corners, com = poses.sites.reshape(T, 2, 4, 3), poses.com
    labels = np.asarray(motion.meta.get("contacts", np.zeros((T, 2))), dtype=bool)
    depth = float(max(0.0, -corners[..., 2].min()))
    centre = corners[..., :2].mean(axis=2)                      # (T, 2, 2)
    both = labels[1:] & labels[:-1]
    speed = np.linalg.norm(np.diff(centre, axis=0), axis=-1) * motion.fps
    n_contact = int(both.sum())
    slow = float((speed[both] <= SLIDE_SPEED).mean()) if n_contact else 1.0
    half = min(min(f.sole_half) for f in robot.config.feet)
    margin = float(motion.meta.get("support_margin", MARGIN_FRACTION * half))
    inside = []
    for t in range(T):
        feet = np.where(labels[t])[0]
        if len(feet) == 0:
            continue
        planes = halfplanes(convex_hull(corners[t, feet, :, :2].reshape(-1, 2)), margin)
        inside.append(np.all(planes[:, :2] @ com[t, :2] - planes[:, 2] <= 1e-4))
    coll = _self_collision_depth(robot, q) if collisions else np.zeros(T)
    return {
        "frames": T, "limit_violations": limit_viol, "sole_depth_mm": 1000 * depth,
        "contact_frames": n_contact, "contact_slow_pct": 100 * slow,
        "max_sole_speed_cm_s": float(100 * speed[both].max()) if n_contact else 0.0,
        "self_collision_mm": float(1000 * coll.max()), "speed_ratio": speed_ratio,
        "com_inside_pct": 100 * float(np.mean(inside)) if inside else 100.0,
        "reversals": velocity_reversals(hinge, motion.fps), "peak_acceleration": peak_acceleration(hinge, motion.fps),
    }

"""Everything the checks share: the motion, the robot, the options and the per-frame results
computed once (kinematics, support, inverse dynamics)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate.dynamics import Dynamics, inverse_dynamics
from motion2robot.validate.kinematics import Kinematics, compute_kinematics
from motion2robot.validate.options import CheckOptions


@dataclass(frozen=True, eq=False)
class Context:
    """labels: (T, 2) contact labels from the motion's meta or None; support: (T, 2, 4) sole
    corners taken as pushing on the floor; low: (T, 2, 4) corners within ``contact_height``."""

    motion: RobotMotion
    robot: Robot
    options: CheckOptions
    kin: Kinematics
    labels: np.ndarray | None
    low: np.ndarray
    support: np.ndarray
    dyn: Dynamics

    @property
    def fps(self) -> float:
        return self.kin.fps


def meta_contacts(motion: RobotMotion) -> np.ndarray | None:
    """The (T, 2) bool contact labels in ``motion.meta["contacts"]``, if present and well-shaped."""
    raw = motion.meta.get("contacts")
    if raw is None:
        return None
    try:
        labels = np.asarray(raw, dtype=bool)
    except (TypeError, ValueError):
        return None
    return labels if labels.shape == (motion.num_frames, 2) else None


def support_corners(kin: Kinematics, options: CheckOptions, labels: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """(low, support), each (T, 2, 4) bool: low = corner within ``contact_height`` of the floor;
    support = low and (slower than ``contact_speed`` horizontally, or its foot labelled in contact)."""
    low = kin.corners[..., 2] < options.contact_height
    slow = np.linalg.norm(kin.corner_vel[..., :2], axis=-1) < options.contact_speed
    ok = slow if labels is None else slow | labels[:, :, None]
    return low, low & ok


def prepare(motion: RobotMotion, robot: Robot, options: CheckOptions) -> Context:
    """Run the shared per-frame pass and the inverse dynamics."""
    kin = compute_kinematics(motion, robot)
    labels = meta_contacts(motion)
    low, support = support_corners(kin, options, labels)
    dyn = inverse_dynamics(kin, robot, support, servo_dynamics=options.servo_dynamics)
    return Context(motion, robot, options, kin, labels, low, support, dyn)

"""Joint limits the safety guard enforces: position range (rad) and velocity (rad/s) per joint."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from motion2robot.errors import RobotConfigError


@dataclass(frozen=True, eq=False)
class JointLimits:
    """names (n,), lower/upper (n,) radians, velocity (n,) rad/s > 0, all in the same order;
    ``compliance`` (n,) radians or None: how far a servo holding its goal may be pushed off it by
    the largest load it resists (torque limit / position gain kp; None: unknown)."""

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    compliance: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = len(self.names)
        for field in ("lower", "upper", "velocity"):
            a = np.array(getattr(self, field), dtype=np.float64).reshape(-1)
            if a.shape != (n,) or not np.all(np.isfinite(a)):
                raise RobotConfigError(f"joint limits: '{field}' must be {n} finite numbers, got {a.shape}")
            a.flags.writeable = False
            object.__setattr__(self, field, a)
        if self.compliance is not None:
            c = np.array(self.compliance, dtype=np.float64).reshape(-1)
            if c.shape != (n,) or not np.all(np.isfinite(c)) or np.any(c < 0):
                raise RobotConfigError(f"joint limits: 'compliance' must be {n} finite numbers >= 0 rad")
            c.flags.writeable = False
            object.__setattr__(self, "compliance", c)
        object.__setattr__(self, "names", tuple(self.names))
        if np.any(self.lower > self.upper) or np.any(self.velocity <= 0):
            bad = [self.names[i] for i in np.where((self.lower > self.upper) | (self.velocity <= 0))[0]]
            raise RobotConfigError(f"joint limits of {', '.join(bad)}: lower > upper or velocity <= 0; fix the robot config")

    @classmethod
    def from_robot(cls, robot: Any) -> JointLimits:
        """From a loaded robot (``joint_names``, ``lower``, ``upper``, ``velocity_limit``; compliance
        = ``torque_limit / kp`` when the robot has both)."""
        torque, kp = getattr(robot, "torque_limit", None), getattr(robot, "kp", None)
        compliance = None
        if torque is not None and kp is not None:
            compliance = np.abs(np.asarray(torque, dtype=np.float64)) / np.asarray(kp, dtype=np.float64)
        return cls(tuple(robot.joint_names), robot.lower, robot.upper, robot.velocity_limit, compliance)

    def select(self, names: Sequence[str]) -> JointLimits:
        """The limits of ``names``, in that order."""
        idx = {n: i for i, n in enumerate(self.names)}
        missing = [n for n in names if n not in idx]
        if missing:
            raise RobotConfigError(f"joints {', '.join(missing)} of the servo map have no limits in the robot; "
                                   "fix the servo map joint names")
        k = [idx[n] for n in names]
        return JointLimits(tuple(names), self.lower[k], self.upper[k], self.velocity[k],
                           None if self.compliance is None else self.compliance[k])

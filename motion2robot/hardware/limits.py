"""Joint limits the safety guard enforces: position range (rad) and velocity (rad/s) per joint."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from motion2robot.errors import RobotConfigError


@dataclass(frozen=True, eq=False)
class JointLimits:
    """names (n,), lower/upper (n,) radians, velocity (n,) rad/s > 0, all in the same order."""

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.names)
        for field in ("lower", "upper", "velocity"):
            a = np.array(getattr(self, field), dtype=np.float64).reshape(-1)
            if a.shape != (n,) or not np.all(np.isfinite(a)):
                raise RobotConfigError(f"joint limits: '{field}' must be {n} finite numbers, got {a.shape}")
            a.flags.writeable = False
            object.__setattr__(self, field, a)
        object.__setattr__(self, "names", tuple(self.names))
        if np.any(self.lower > self.upper) or np.any(self.velocity <= 0):
            bad = [self.names[i] for i in np.where((self.lower > self.upper) | (self.velocity <= 0))[0]]
            raise RobotConfigError(f"joint limits of {', '.join(bad)}: lower > upper or velocity <= 0; fix the robot config")

    @classmethod
    def from_robot(cls, robot: Any) -> JointLimits:
        """From a loaded robot (``joint_names``, ``lower``, ``upper``, ``velocity_limit``)."""
        return cls(tuple(robot.joint_names), robot.lower, robot.upper, robot.velocity_limit)

    def select(self, names: Sequence[str]) -> JointLimits:
        """The limits of ``names``, in that order."""
        idx = {n: i for i, n in enumerate(self.names)}
        missing = [n for n in names if n not in idx]
        if missing:
            raise RobotConfigError(f"joints {', '.join(missing)} of the servo map have no limits in the robot; "
                                   "fix the servo map joint names")
        k = [idx[n] for n in names]
        return JointLimits(tuple(names), self.lower[k], self.upper[k], self.velocity[k])

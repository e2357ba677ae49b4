"""Feasibility of a RobotMotion on its robot, in MuJoCo: limits, collisions, floor, balance,
torques, physics playback and trajectory figures -> :class:`FeasibilityReport`.

``check(motion, robot, options=None)`` runs them all; each check family has its own module
(limits, collision, ground, balance, dynamics, rollout, trajectory), the sentences live in
:mod:`~motion2robot.validate.reasons` and the text table in :mod:`~motion2robot.validate.table`.
"""

from motion2robot.validate.api import check
from motion2robot.validate.options import CheckOptions
from motion2robot.validate.report import CHECK_NAMES, FeasibilityReport
from motion2robot.validate.table import verdict_table

__all__ = ["CHECK_NAMES", "CheckOptions", "FeasibilityReport", "check", "verdict_table"]

"""Robots: MuJoCo model + validated config (:class:`Robot`), resolved from ``op3`` | ``menagerie:NAME`` | a path."""

from motion2robot.robot.config import RobotConfig, load_config
from motion2robot.robot.loader import build_robot, load_robot
from motion2robot.robot.robot import Robot

__all__ = ["Robot", "RobotConfig", "load_robot", "load_config", "build_robot"]

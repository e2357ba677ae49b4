"""Retargeting: HumanMotion -> RobotMotion by a casadi IK problem solved over all frames at once."""

from motion2robot.retarget.api import RetargetOptions, retarget, retarget_and_check, whole_body
from motion2robot.retarget.costs import FRAME_TERMS, Weights
from motion2robot.retarget.scale import Scale, auto_scale

__all__ = ["FRAME_TERMS", "RetargetOptions", "Scale", "Weights", "auto_scale", "retarget", "retarget_and_check",
           "whole_body"]

"""trajectory: the robot's root path against the human's scaled root path (figures only)."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.robot import load_robot
from motion2robot.robot_motion import RobotMotion
from motion2robot.validate.context import prepare
from motion2robot.validate.options import CheckOptions
from motion2robot.validate.trajectory import trajectory


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def circle_walk(robot, radius=0.5, seconds=4.0, fps=20.0):
    """The nominal posture carried round a circle, facing along the path (feet skate: only the path matters)."""
    t = np.arange(int(seconds * fps)) / fps
    ang = 2 * np.pi * t / seconds
    q = np.tile(robot.nominal_qpos, (len(t), 1))
    q[:, 0], q[:, 1] = radius * np.sin(ang), radius * (1 - np.cos(ang))
    q[:, 3], q[:, 6] = np.cos(ang / 2), np.sin(ang / 2)
    return q, fps


def test_skipped_without_the_human_path(op3):
    q, fps = circle_walk(op3)
    out = trajectory(prepare(RobotMotion(q, fps, op3.joint_names, "op3"), op3, CheckOptions()))
    assert out["ok"] and "skipped" in out


def test_following_the_path_gives_zero_error(op3):
    q, fps = circle_walk(op3)
    mo = RobotMotion(q, fps, op3.joint_names, "op3", meta={"human_root_xy": q[:, :2].tolist()})
    out = trajectory(prepare(mo, op3, CheckOptions()))
    assert out["ok"] and out["mean_error_m"] == pytest.approx(0.0, abs=1e-9)
    assert out["heading_error_mean_deg"] == pytest.approx(0.0, abs=1e-6)
    assert out["path_length_ratio"] == pytest.approx(1.0)
    assert out["human_path_m"] == pytest.approx(2 * np.pi * 0.5, rel=0.02)


def test_a_smaller_circle_shows_position_and_path_length_error(op3):
    q, fps = circle_walk(op3, radius=0.4)
    human, _ = circle_walk(op3, radius=0.5)
    mo = RobotMotion(q, fps, op3.joint_names, "op3", meta={"human_root_xy": human[:, :2].tolist()})
    out = trajectory(prepare(mo, op3, CheckOptions()))
    assert out["ok"]  # a figure, never a verdict
    assert out["max_error_m"] == pytest.approx(0.2, abs=0.01)  # opposite side of the circles
    assert out["path_length_ratio"] == pytest.approx(0.8, rel=0.02)
    assert out["heading_error_max_deg"] < 1.0  # same directions of travel


def test_heading_error_of_a_path_walked_the_other_way(op3):
    q, fps = circle_walk(op3)
    human = q[:, :2].copy()
    human[:, 1] *= -1  # the mirrored circle: the human turns right, the robot left
    mo = RobotMotion(q, fps, op3.joint_names, "op3", meta={"human_root_xy": human.tolist()})
    out = trajectory(prepare(mo, op3, CheckOptions()))
    assert out["heading_error_max_deg"] > 90

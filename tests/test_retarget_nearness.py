"""The keypoint error the legs policy compares two passing modes by (retarget/nearness.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2robot.motion import read_motion
from motion2robot.retarget import RetargetOptions, retarget
from motion2robot.retarget.nearness import keypoint_error
from motion2robot.retarget.scale import auto_scale
from motion2robot.robot import load_robot

DEMO = Path(__file__).resolve().parents[1] / "motion2robot" / "data" / "demo_wave_squat.npy"


@pytest.fixture(scope="module")
def made():
    robot = load_robot("op3")
    human = read_motion(DEMO)[0]
    human = human.with_(positions=np.asarray(human.positions)[:60])
    return robot, human, retarget(human, robot, RetargetOptions(tempo=1.0, legs="whole"))


def test_a_human_moved_away_is_farther_by_the_scaled_distance_and_its_pose_as_near(made) -> None:
    robot, human, motion = made
    scale = auto_scale(human, robot)
    near = keypoint_error(motion, human, robot)
    assert 0.0 < near < 0.1  # the demo is tracked within centimetres
    away = human.with_(positions=np.asarray(human.positions) + [2.0, 0.0, 0.0])  # 2 m along x
    far = keypoint_error(motion, away, robot, scale)
    assert far == pytest.approx(2.0 * scale.legs, abs=near)  # the targets moved 2 m x legs
    assert keypoint_error(motion, away, robot, scale, pose=True) == pytest.approx(
        keypoint_error(motion, human, robot, scale, pose=True))


def test_the_shorter_of_the_two_sets_the_frames(made) -> None:
    robot, human, motion = made
    short = human.with_(positions=np.asarray(human.positions)[:30])
    first = motion.with_(qpos=motion.qpos[:30])
    assert keypoint_error(motion, short, robot, auto_scale(human, robot)) == pytest.approx(
        keypoint_error(first, human.with_(positions=np.asarray(human.positions)[:30]), robot, auto_scale(human, robot)))

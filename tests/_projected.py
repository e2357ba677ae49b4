"""The real clip the projection tests share, projected once per test process."""

from __future__ import annotations

import functools

import numpy as np

from motion2robot.projection import chosen_solve, hinge_rms, project
from tests._shared import MOTIONS
from tests._tensor import FakeTensor

#: A short real clip: standing, raising and moving the left arm overhead (HumanML3D, 70 frames).
CLIP = "humanml3d_joints/M010968.npy"


def op3():
    from motion2robot.robot import load_robot

    return load_robot("op3")


@functools.lru_cache(maxsize=1)
def clip_projection():
    """(the raw joints, their projection onto op3), the input passed as a duck-typed tensor."""
    raw = np.load(MOTIONS / CLIP)
    return raw, project(FakeTensor(raw), "op3")


def direct_gap(p, options=None) -> float:
    """RMS (rad) between the robot motion and the retargeting (at its tempo and legs) of the
    robot's keypoints mapped back without the correction."""
    return hinge_rms(p.robot_motion, chosen_solve(p.robot_motion, op3(), options)(p.direct))


def solved():
    """The correction rounds (what a slowed motion, whose frames fall between the human's, goes
    through) measured at x1.0: the exact reach off."""
    from motion2robot.retarget import RetargetOptions

    return RetargetOptions(reach=False)

"""Exact reach: a robot-shaped human motion (the robot's own motion in the human's space) is
retargeted to exactly its poses; any other motion is solved as before."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from motion2robot.motion.human import SMPL22
from motion2robot.projection import hinge_rms, project_motion
from motion2robot.retarget import RetargetOptions, retarget, retarget_and_check
from motion2robot.retarget.api import whole_body
from motion2robot.retarget.exact import exact_motion
from motion2robot.retarget.reach import LIMIT_SLACK, TOLERANCE_M, rigid_bones, robot_scale, robot_shaped
from motion2robot.robot_motion import RobotMotion
from tests._demo import demo_clip, op3

FIXED = RetargetOptions(tempo=1.0, legs="whole")


_robot = op3


@functools.lru_cache(maxsize=1)
def _demo():
    """The bundled demo clip (first 60 frames), its whole-body robot motion and that motion mapped back."""
    human = demo_clip(60)
    motion = retarget(human, _robot(), FIXED)
    return human, motion, project_motion(motion, _robot(), human)


def test_every_scale_group_has_a_rigid_bone_on_op3() -> None:
    bones = rigid_bones(_robot())
    assert {b.group for b in bones} == {"legs", "arms", "height"}
    # the shank and the forearms are rigid; the chain hip -> ankle is not one bone of the tree
    names = {(SMPL22[b.parent], SMPL22[b.child]) for b in bones}
    assert ("left_elbow", "left_wrist") in names and ("pelvis", "neck") in names
    assert all(b.length > 0.01 for b in bones)


def test_a_human_clip_is_not_robot_shaped() -> None:
    human, _, _ = _demo()
    assert robot_scale(human.positions, _robot()) is None  # a person's proportions are not the robot's
    assert robot_shaped(human.positions, _robot()) is None and exact_motion(human, _robot()) is None


def test_the_robots_own_motion_mapped_back_is_reached_exactly() -> None:
    _, motion, back = _demo()
    scale = robot_scale(back.positions, _robot())
    assert scale is not None
    for k in ("legs", "arms", "height"):  # the scale the motion was made at, not the leg chain's
        assert getattr(scale, k) == pytest.approx(motion.meta["scale"][k], rel=1e-9)
    again = whole_body(back, _robot(), FIXED)
    assert again.meta["reached"] is True and "exact reach" in again.meta["solver"]["method"]
    assert again.meta["solver"]["max_residual"] < TOLERANCE_M
    assert np.abs(again.qpos - motion.qpos).max() < 1e-6  # root and hinges
    solved = whole_body(back, _robot(), RetargetOptions(tempo=1.0, legs="whole", reach=False))
    assert "reached" not in solved.meta and hinge_rms(solved, motion) > 1e-3  # what the solve alone gives


def test_float32_rounding_still_reaches_and_a_millimetre_does_not() -> None:
    _, motion, back = _demo()
    f32 = back.with_(positions=back.positions.astype(np.float32).astype(np.float64))
    assert hinge_rms(exact_motion(f32, _robot(), FIXED), motion) < 1e-5
    moved = back.with_(positions=back.positions + 1e-3 * np.random.default_rng(1).standard_normal(back.positions.shape))
    assert exact_motion(moved, _robot(), FIXED) is None


def test_a_pose_beyond_a_joint_limit_is_not_reached() -> None:
    human, motion, _ = _demo()
    rb = _robot()
    j = rb.joint_index("l_knee")
    Q = motion.qpos.copy()
    beyond = rb.upper[j] + 0.2 if abs(rb.upper[j] - Q[:, 7 + j].max()) < abs(Q[:, 7 + j].min() - rb.lower[j]) \
        else rb.lower[j] - 0.2
    Q[20:25, 7 + j] = beyond
    off = project_motion(RobotMotion(qpos=Q, fps=motion.fps, joint_names=motion.joint_names, robot=motion.robot,
                                     meta={"scale": motion.meta["scale"], "tempo": 1.0}), rb, human)
    assert robot_scale(off.positions, rb) is not None  # rigid bones as the robot's ...
    assert robot_shaped(off.positions, rb) is None  # ... but frame 20's pose is out of the knee's range
    assert LIMIT_SLACK < 0.2


def test_the_policy_judges_the_exact_poses_first() -> None:
    """The default retargeting (tempo and legs auto) of the robot-shaped motion tries its exact
    poses before any legs mode, and returns them when they pass the checks."""
    _, motion, back = _demo()
    again, report = retarget_and_check(back, _robot())
    assert again.meta["reached"] is True and again.meta["fallback"] is None and again.meta["tempo"] == 1.0
    assert report.feasible and again.meta["attempts"] == [{"legs": "whole", "tempo": 1.0, "feasible": True,
                                                           "failed": []}]
    assert hinge_rms(again, motion) < 1e-6

"""Per-frame forward kinematics of a trajectory: the compiled loop gives MuJoCo's own values, as
the Python loop does, for sites, bodies, hinge anchors and a subtree CoM."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from motion2robot.robot import load_robot, poses
from motion2robot.robot.poses import frame_poses
from motion2robot.validate import examples


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


@pytest.mark.parametrize("compiled", [True, False], ids=["C loop", "Python loop"])
def test_frame_poses_are_mujocos(op3, compiled, monkeypatch):
    if not compiled:
        monkeypatch.setattr(poses, "library", lambda: None)
    elif poses.library() is None:
        pytest.skip("no C compiler: the Python loop runs")
    q = examples.waving(op3, seconds=1.0).qpos
    sites, bodies, joints = [int(s) for s in op3.keypoint_sites], [int(op3.torso_body), 1], [int(op3.joint_ids[5])]
    got = frame_poses(op3.model, q, sites, bodies, joints, com_body=int(op3.root_body))
    d = mujoco.MjData(op3.model)
    for t in (0, len(q) // 2, len(q) - 1):
        d.qpos[:] = q[t]
        mujoco.mj_kinematics(op3.model, d)
        mujoco.mj_comPos(op3.model, d)
        assert np.array_equal(got.sites[t], d.site_xpos[sites])
        assert np.array_equal(got.xpos[t], d.xpos[bodies]) and np.array_equal(got.xmat[t], d.xmat[bodies])
        assert np.array_equal(got.anchors[t], d.xanchor[joints])
        assert np.array_equal(got.com[t], d.subtree_com[op3.root_body])
    assert not np.allclose(got.sites[0], got.sites[len(q) // 2])  # the arm moved
    empty = frame_poses(op3.model, q)
    assert empty.sites.shape == (len(q), 0, 3) and empty.com is None

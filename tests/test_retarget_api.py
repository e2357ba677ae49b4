"""Retargeting on real clips and on reachable targets; the IPOPT baseline agrees with the fast path."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.motion import HumanMotion
from motion2robot.motion.human import KP, SMPL22
from motion2robot.retarget import RetargetOptions, Weights, whole_body as retarget
from motion2robot.retarget.compiled import compiled_problem
from motion2robot.retarget.metrics import acceptance
from motion2robot.retarget.scale import Scale
from motion2robot.robot import load_robot
from tests._shared import MOTIONS, requires_shared


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def _read(name: str) -> HumanMotion:
    from motion2robot.motion import read_motion

    return read_motion(MOTIONS / name)[0]


def _smooth_trajectory(robot, T: int, fps: float, seed: int) -> np.ndarray:
    """Random smooth hinge trajectories inside the limits and under half the velocity limit."""
    rng = np.random.default_rng(seed)
    lo, hi = robot.lower, robot.upper
    mid, half = (lo + hi) / 2, (hi - lo) / 2
    t = np.arange(T) / fps
    phase = rng.uniform(0, 2 * np.pi, size=(2, robot.n_joints))
    freq = rng.uniform(0.1, 0.25, size=robot.n_joints)
    shape = 0.6 * np.sin(2 * np.pi * freq * t[:, None] + phase[0]) + 0.2 * np.sin(4 * np.pi * freq * t[:, None] + phase[1])
    q = mid + 0.5 * half * shape
    q = robot.nominal_qpos[7:] + 0.5 * (q - robot.nominal_qpos[7:])  # stay near a standing posture
    return np.clip(q, lo, hi)


def test_reachable_targets_are_reached(op3):
    """Keypoints from the robot's own FK along a smooth trajectory: retargeting with unit scale,
    no contacts/balance and only the tracking terms recovers them to well under 1 mm."""
    T, fps = 30, 20.0
    hinges = _smooth_trajectory(op3, T, fps, seed=1)
    qpos = np.tile(op3.nominal_qpos, (T, 1))
    qpos[:, 7:] = hinges
    qpos[:, 0] = np.linspace(0.0, 0.05, T)
    points = compiled_problem(op3).points_eval(T)
    _, corners, _, _ = points(qpos)
    qpos[:, 2] -= corners.reshape(T, -1, 3)[..., 2].min(axis=1)  # lowest sole corner on the floor
    kp_sites, corners, _, gaps = points(qpos)
    assert corners.reshape(T, -1, 3)[..., 2].min() > -1e-9 and gaps.min() > 0  # feasible targets
    kp = kp_sites.reshape(T, -1, 3)
    pos = np.zeros((T, len(SMPL22), 3))
    pos[:] = kp[:, [op3.keypoints.index("pelvis")]]
    for i, name in enumerate(op3.keypoints):
        pos[:, KP[name]] = kp[:, i]
    human = HumanMotion(pos, fps, meta={"source": "fk"})
    zero = {k: 0.0 for k in ("pelvis_heading", "torso_up", "foot_heading", "sole_flat", "posture", "velocity", "acceleration")}
    opts = RetargetOptions(balance=False, contacts=False, scale=Scale(1.0, 1.0, 1.0),
                           weights=Weights(**zero), iterations=(40, 10))
    out = retarget(human, op3, opts)
    err = np.array(out.meta["solver"]["residual_per_frame"])
    assert err.mean() < 1e-3, err.mean()


@requires_shared
def test_arm_raise_clip_on_op3(op3):
    human = _read("humanml3d_joints/M010968.npy")
    out = retarget(human, op3)
    assert out.qpos.shape == (human.num_frames, op3.nq)
    a = acceptance(out, op3, collisions=False)
    assert a["limit_violations"] == 0
    assert a["sole_depth_mm"] <= 2.0
    assert a["speed_ratio"] <= 1.0 + 1e-9
    assert a["contact_slow_pct"] >= 99.0
    assert a["com_inside_pct"] == 100.0
    meta = out.meta
    assert {"source", "clip", "prompt", "scale", "solver", "contacts", "human_root_xy", "robot_hash"} <= set(meta)
    assert len(meta["solver"]["residual_per_frame"]) == human.num_frames
    assert np.array(meta["human_root_xy"]).shape == (human.num_frames, 2)
    assert 0.2 < meta["scale"]["legs"] < 0.4  # OP3 legs are ~0.22 m against ~0.8 m for the clip
    q = out.qpos[:, 3:7]
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0)


@requires_shared
def test_unreachable_target_keeps_limits(op3):
    """A wrist target far out of reach: the joint limits still hold and the residual is reported."""
    human = _read("humanml3d_joints/M010968.npy")
    pos = np.array(human.positions)
    pos[20:30, KP["left_wrist"]] += np.array([0.0, 3.0, 2.0])
    out = retarget(human.with_(positions=pos), op3)
    hinge = out.qpos[:, 7:]
    assert np.all(hinge >= op3.lower - 1e-9) and np.all(hinge <= op3.upper + 1e-9)
    res = np.array(out.meta["solver"]["residual_per_frame"])
    assert res[20:30].min() > 2 * res[:15].max()


@requires_shared
def test_ipopt_baseline_gives_the_same_kind_of_answer(op3):
    from motion2robot.motion.ops import trim

    human = trim(_read("humanml3d_joints/M010968.npy"), 0, 12)
    fast = retarget(human, op3)
    slow = retarget(human, op3, RetargetOptions(solver="ipopt"))
    ef = np.mean(fast.meta["solver"]["residual_per_frame"])
    es = np.mean(slow.meta["solver"]["residual_per_frame"])
    assert abs(ef - es) < 0.01  # metres of mean keypoint error
    assert np.all(slow.qpos[:, 7:] >= op3.lower - 1e-9) and np.all(slow.qpos[:, 7:] <= op3.upper + 1e-9)

"""The shipped Menagerie configs (unitree_g1, unitree_h1) load, stand flat and respect the models."""

import mujoco
import numpy as np
import pytest

from motion2robot.robot import load_robot
from tests._shared import requires_menagerie

pytestmark = requires_menagerie



def _contacts(robot, qpos):
    d = mujoco.MjData(robot.model)
    d.qpos[:] = qpos
    mujoco.mj_forward(robot.model, d)
    return d.ncon


# name, DOF, mass of the menagerie model (kg), height range of the highest keypoint (m),
# top of the model's geometry (m) around the published standing height
CASES = [
    ("menagerie:unitree_g1", 29, 33.34, (1.15, 1.30)),
    ("menagerie:unitree_h1", 19, 51.44, (1.60, 1.75)),
]


@pytest.mark.parametrize("name, dof, mass, height", CASES)
def test_loads_and_stands_flat_without_self_contact(menagerie_env, name, dof, mass, height):
    r = load_robot(name)
    assert r.n_joints == dof and r.mass == pytest.approx(mass, abs=0.01)
    assert height[0] < r.height < height[1]
    d = r.new_data()
    corners = d.site_xpos[r.sole_sites.ravel(), 2]
    assert np.all(np.abs(corners) < 0.002), corners  # all 8 sole corners on the floor
    assert _contacts(r, r.nominal_qpos) == 0
    # the contact check is live: crossing the legs collides
    q = r.nominal_qpos.copy()
    left = [i for i, n in enumerate(r.joint_names) if n.startswith("left_hip_roll")][0]
    right = [i for i, n in enumerate(r.joint_names) if n.startswith("right_hip_roll")][0]
    q[7 + left], q[7 + right] = r.lower[left], r.upper[right]
    assert _contacts(r, q) > 0
    # knees bent, pelvis upright (hip + knee + ankle pitch = 0 on both legs)
    assert r.nominal_qpos[3] == 1.0
    knees = [i for i, n in enumerate(r.joint_names) if "knee" in n]
    assert all(r.nominal_qpos[7 + i] > 0.1 for i in knees)


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_ranges_are_the_models_and_torques_its_actuator_limits(menagerie_env, name):
    r = load_robot(name)
    raw = mujoco.MjModel.from_xml_path(r.mjcf_path)
    for i, n in enumerate(r.joint_names):
        j = raw.joint(n)
        assert (r.lower[i], r.upper[i]) == pytest.approx(tuple(j.range)), n
        if raw.jnt_actfrclimited[j.id]:
            model_torque = max(abs(raw.jnt_actfrcrange[j.id]))
        else:  # H1: motor actuators, gear 1, ctrl = torque
            a = raw.actuator(n)
            assert a.gear[0] == 1 and raw.actuator_biastype[a.id] == 0
            model_torque = max(abs(a.ctrlrange))
        assert r.torque_limit[i] == pytest.approx(model_torque), n
        assert lo_ok(r, i)
    assert np.all(r.velocity_limit >= 9) and np.all(r.velocity_limit <= 37)
    assert np.all(r.kp > 0) and np.all(r.kp * 0.1 <= r.torque_limit)  # kp x 0.1 rad within the torque limit


def lo_ok(r, i):
    return r.lower[i] <= r.nominal_qpos[7 + i] <= r.upper[i]


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_keypoints_cover_the_skeleton_with_human_like_layout(menagerie_env, name):
    r = load_robot(name)
    d = r.new_data()
    p = {k: d.site_xpos[s] for k, s in zip(r.keypoints, r.keypoint_sites)}
    for side, sign in (("left", 1), ("right", -1)):
        assert sign * p[f"{side}_hip"][1] > 0.05 and sign * p[f"{side}_shoulder"][1] > 0.1
        z = [p[f"{side}_{j}"][2] for j in ("shoulder", "elbow", "wrist")]
        assert z[0] > z[1] > z[2]  # arms hang down at the nominal pose
        z = [p[f"{side}_{j}"][2] for j in ("hip", "knee", "ankle", "foot")]
        assert z[0] > z[1] > z[2] > z[3] > 0.0
        assert p[f"{side}_foot"][0] > p[f"{side}_ankle"][0]  # toes forward (+x)
    assert p["head"][2] > p["neck"][2] > p["spine3"][2] > p["pelvis"][2]
    # mirror symmetric
    for k in p:
        if k.startswith("left_"):
            q = p["right_" + k[5:]]
            assert p[k] == pytest.approx(q * [1, -1, 1], abs=1e-3), k


def test_g1_stands_on_its_servos(menagerie_env):
    """The G1's gains hold the nominal posture as a statue in the validator's physics model for 4 s,
    also after a 0.2 m/s push of the pelvis (the H1 does not: see the KNOWN LIMIT in its config)."""
    from motion2robot.validate.models import physics_model

    r = load_robot("menagerie:unitree_g1")
    m = physics_model(r)
    for push in (0.0, 0.2):
        d = mujoco.MjData(m)
        d.qpos[:] = r.nominal_qpos
        d.qpos[2] += 0.002
        d.qvel[0] = push
        d.ctrl[:] = r.nominal_qpos[7:]
        while d.time < 4.0:
            mujoco.mj_step(m, d)
        tilt = 2 * np.arcsin(np.linalg.norm(d.qpos[4:6]))
        assert tilt < 0.1 and d.qpos[2] > r.nominal_qpos[2] - 0.03, (push, tilt, d.qpos[2])

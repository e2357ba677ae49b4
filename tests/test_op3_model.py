"""The bundled OP3 model (robots/op3/op3.xml + op3.toml): facts, limits, self-collision, standing."""

from __future__ import annotations

import copy
from pathlib import Path

import mujoco
import numpy as np
import pytest

from motion2robot.robot.config import load_config
from motion2robot.robot.limit_check import ClearanceProbe, check_limits, free_extent, limbs
from motion2robot.robot.loader import load_robot
from tests._shared import MENAGERIE, requires_menagerie

OP3_DIR = Path(__file__).resolve().parents[1] / "robots" / "op3"
MJCF = OP3_DIR / "op3.xml"
TOML = OP3_DIR / "op3.toml"

# Facts sheet (../shared/facts/op3.md): body -> (parent, offset, joint, axis, mass).
FACTS = {
    "head_pan_link": ("body_link", (-0.001, 0, 0.1365), "head_pan", (0, 0, 1), 0.01176),
    "head_tilt_link": ("head_pan_link", (0.01, 0.019, 0.0285), "head_tilt", (0, -1, 0), 0.13631),
    "l_sho_pitch_link": ("body_link", (-0.001, 0.06, 0.111), "l_sho_pitch", (0, 1, 0), 0.01176),
    "l_sho_roll_link": ("l_sho_pitch_link", (0.019, 0.0285, -0.01), "l_sho_roll", (-1, 0, 0), 0.17758),
    "l_el_link": ("l_sho_roll_link", (0, 0.0904, -0.0001), "l_el", (1, 0, 0), 0.04127),
    "r_sho_pitch_link": ("body_link", (-0.001, -0.06, 0.111), "r_sho_pitch", (0, -1, 0), 0.01176),
    "r_sho_roll_link": ("r_sho_pitch_link", (0.019, -0.0285, -0.01), "r_sho_roll", (-1, 0, 0), 0.17758),
    "r_el_link": ("r_sho_roll_link", (0, -0.0904, -0.0001), "r_el", (1, 0, 0), 0.04127),
    "l_hip_yaw_link": ("body_link", (0, 0.035, 0), "l_hip_yaw", (0, 0, -1), 0.01181),
    "l_hip_roll_link": ("l_hip_yaw_link", (-0.024, 0, -0.0285), "l_hip_roll", (-1, 0, 0), 0.17886),
    "l_hip_pitch_link": ("l_hip_roll_link", (0.0241, 0.019, 0), "l_hip_pitch", (0, 1, 0), 0.11543),
    "l_knee_link": ("l_hip_pitch_link", (0, 0, -0.11015), "l_knee", (0, 1, 0), 0.04015),
    "l_ank_pitch_link": ("l_knee_link", (0, 0, -0.11), "l_ank_pitch", (0, -1, 0), 0.17886),
    "l_ank_roll_link": ("l_ank_pitch_link", (-0.0241, -0.019, 0), "l_ank_roll", (1, 0, 0), 0.06934),
    "r_hip_yaw_link": ("body_link", (0, -0.035, 0), "r_hip_yaw", (0, 0, -1), 0.01181),
    "r_hip_roll_link": ("r_hip_yaw_link", (-0.024, 0, -0.0285), "r_hip_roll", (-1, 0, 0), 0.17886),
    "r_hip_pitch_link": ("r_hip_roll_link", (0.0241, -0.019, 0), "r_hip_pitch", (0, -1, 0), 0.11543),
    "r_knee_link": ("r_hip_pitch_link", (0, 0, -0.11015), "r_knee", (0, -1, 0), 0.04015),
    "r_ank_pitch_link": ("r_knee_link", (0, 0, -0.11), "r_ank_pitch", (0, 1, 0), 0.17886),
    "r_ank_roll_link": ("r_ank_pitch_link", (-0.0241, 0.019, 0), "r_ank_roll", (1, 0, 0), 0.06934),
}
SERVO_IDS = ("r_sho_pitch l_sho_pitch r_sho_roll l_sho_roll r_el l_el r_hip_yaw l_hip_yaw r_hip_roll l_hip_roll "
             "r_hip_pitch l_hip_pitch r_knee l_knee r_ank_pitch l_ank_pitch r_ank_roll l_ank_roll head_pan head_tilt").split()


@pytest.fixture(scope="module")
def model() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(MJCF))


@pytest.fixture(scope="module")
def config():
    return load_config(TOML)


def test_tree_follows_the_facts_sheet(model):
    assert model.nbody == 22 and model.njnt == 21 and model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
    assert model.body("body_link").pos.tolist() == pytest.approx([0, 0, 0.3])
    assert model.body("body_link").mass[0] == pytest.approx(1.3493)
    assert model.body("body_link").ipos == pytest.approx([-0.01501, 0.00013, 0.06582])
    for body, (parent, offset, joint, axis, mass) in FACTS.items():
        b = model.body(body)
        assert model.body(int(b.parentid[0])).name == parent
        assert b.pos == pytest.approx(offset, abs=1e-9)
        assert b.quat == pytest.approx([1, 0, 0, 0])
        assert b.mass[0] == pytest.approx(mass)
        j = model.joint(joint)
        assert int(j.bodyid[0]) == b.id and j.axis == pytest.approx(axis)
        assert (j.damping[0], j.armature[0], j.frictionloss[0]) == pytest.approx((1.084, 0.045, 0.03))
    assert float(model.body_mass.sum()) == pytest.approx(3.1475, abs=1e-3)
    assert np.all(model.body_inertia[1:] > 0)


def test_actuators_are_xm430_position_servos(model, config):
    assert model.nu == 20
    for a in range(model.nu):
        act = model.actuator(a)
        joint = model.joint(int(act.trnid[0]))
        assert act.name == joint.name
        assert act.gainprm[0] == pytest.approx(21.1) and act.biasprm[1] == pytest.approx(-21.1)
        assert act.forcerange == pytest.approx([-4.1, 4.1]) and act.forcelimited
        assert act.ctrlrange == pytest.approx(joint.range)
    assert (config.default_kp, config.default_torque, config.default_velocity) == (21.1, 4.1, 4.8)


def test_toml_limits_equal_mjcf_ranges_and_have_reasons(model, config):
    hinges = [model.joint(j).name for j in range(1, model.njnt)]
    assert sorted(config.joints) == sorted(hinges)
    for name in hinges:
        jc = config.joint(name)
        assert model.jnt_limited[model.joint(name).id]
        assert model.joint(name).range == pytest.approx(jc.range)
        assert len(jc.reason) > 20
        lo, hi = jc.range
        assert lo <= config.nominal.get(name, 0.0) <= hi


def test_knees_and_elbows_bend_one_way(model):
    # Left pitch axis +y: positive knee angle swings the shin backwards (flexion); right is mirrored.
    rng = {n: tuple(model.joint(n).range) for n in ("l_knee", "r_knee", "l_el", "r_el")}
    assert rng["l_knee"][0] == 0.0 and rng["l_knee"][1] > 1.5
    assert rng["r_knee"][1] == 0.0 and rng["r_knee"][0] < -1.5
    assert rng["l_el"][1] == 0.0 and rng["r_el"][0] == 0.0
    # Check the direction physically: flexing the left knee moves the ankle behind the knee.
    d = mujoco.MjData(model)
    d.qpos[model.joint("l_knee").qposadr[0]] = 1.0
    d.qpos[model.joint("r_knee").qposadr[0]] = -1.0
    mujoco.mj_kinematics(model, d)
    for side in "lr":
        knee, ankle = d.body(f"{side}_knee_link").xpos, d.body(f"{side}_ank_pitch_link").xpos
        assert ankle[0] < knee[0] - 0.05
    # and folding the left elbow from the hanging arm brings the hand towards the midline.
    d.qpos[:] = 0
    d.qpos[3] = 1
    d.qpos[model.joint("l_sho_roll").qposadr[0]] = 1.2
    mujoco.mj_kinematics(model, d)
    y0 = d.site("l_hand").xpos[1]
    d.qpos[model.joint("l_el").qposadr[0]] = -0.5
    mujoco.mj_kinematics(model, d)
    assert d.site("l_hand").xpos[1] < y0 - 0.03


def test_feet_soles_and_sites(model, config):
    for side, s in (("l", 1), ("r", -1)):
        a, b = model.geom(f"{side}_sole_a"), model.geom(f"{side}_sole_b")
        assert a.size == pytest.approx([0.0635, 0.028, 0.004]) and b.size == pytest.approx([0.057, 0.039, 0.004])
        assert a.pos == pytest.approx([0.024, s * 0.013, -0.0265]) and b.pos == pytest.approx([0.024, s * 0.013, -0.0265])
        assert model.site(f"{side}_hand").pos == pytest.approx([-0.019, s * 0.145, 0])
        assert model.site(f"{side}_sole").pos == pytest.approx([0.024, s * 0.013, -0.0305])
    for foot in config.feet:
        assert foot.sole_half == pytest.approx((0.0635, 0.039))
        assert foot.sole_center[2] == pytest.approx(-0.0305)
    assert model.site("head_top").bodyid == model.body("head_tilt_link").id


def test_servo_map_matches_the_op3_framework(config):
    sm = config.servos
    assert (sm.model, sm.baud, sm.ticks_per_rev, sm.center) == ("XM430-W350", 2_000_000, 4096, 2048)
    assert {s.joint: s.id for s in sm.servos} == {j: i + 1 for i, j in enumerate(SERVO_IDS)}
    assert all(s.sign == 1 and s.offset == 0 for s in sm.servos)


def test_loader_nominal_pose_stands_flat_over_the_feet():
    robot = load_robot("op3")
    d = mujoco.MjData(robot.model)
    d.qpos[:] = robot.nominal_qpos
    mujoco.mj_forward(robot.model, d)
    corners = d.site_xpos[robot.sole_sites.ravel()]
    assert np.abs(corners[:, 2]).max() < 1e-6  # both soles flat on z = 0
    com = d.subtree_com[robot.root_body]
    assert corners[:, 0].min() + 0.02 < com[0] < corners[:, 0].max() - 0.02
    assert abs(com[1]) < 0.01
    assert set(robot.keypoints) >= {"pelvis", "left_hip", "right_knee", "left_ankle", "right_foot",
                                    "head", "left_shoulder", "right_elbow", "left_wrist", "right_wrist"}
    # hands beside the thighs without touching: clearance at the nominal pose
    probe = ClearanceProbe(robot.model)
    dist, _ = probe.clearance(probe.qpos(dict(robot.config.nominal)))
    assert dist > 0.005


def test_no_self_collision_at_limit_sweeps_and_same_limb_corners(model, config):
    probes = check_limits(model, config.nominal)
    n_hinges = model.njnt - 1
    groups = limbs(model)
    assert sorted(len(g) for g in groups.values()) == [2, 3, 3, 6, 6]
    n_corners = 4 * sum(len(g) * (len(g) - 1) // 2 for g in groups.values())
    assert len(probes) == 2 * n_hinges + n_corners
    worst = min(probes, key=lambda p: p.min_distance)
    assert worst.min_distance > -0.001, f"{worst.label}: {worst.pair} penetrate {-worst.min_distance * 1000:.1f} mm"


def test_limit_check_catches_a_knee_bent_into_the_hip(model, config):
    bent = copy.deepcopy(model)
    bent.jnt_range[bent.joint("l_knee").id] = (0.0, 2.5)
    worst = min(check_limits(bent, config.nominal), key=lambda p: p.min_distance)
    assert worst.min_distance < -0.001 and "l_knee" in worst.label
    stop, pair = free_extent(model, config.nominal, "l_knee", 2.5)
    assert 2.0 < stop < 2.5 and set(pair) == {"l_hip_servos", "l_ankle_servos"}


@requires_menagerie
def test_anchors_and_mass_match_the_menagerie_op3(model):
    path = MENAGERIE / "robotis_op3" / "op3.xml"
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    ref = mujoco.MjModel.from_xml_path(str(path))
    d, dr = mujoco.MjData(model), mujoco.MjData(ref)
    names = [model.joint(j).name for j in range(1, model.njnt)]
    ours = np.array([model.joint(n).qposadr[0] for n in names])
    theirs = np.array([ref.joint(n).qposadr[0] for n in names])
    jid_ours = np.array([model.joint(n).id for n in names])
    jid_theirs = np.array([ref.joint(n).id for n in names])
    lo, hi = model.jnt_range[jid_ours].T
    rng = np.random.default_rng(7)
    worst = 0.0
    for q in rng.uniform(lo, hi, size=(1000, len(names))):
        for m_, d_, adr in ((model, d, ours), (ref, dr, theirs)):
            d_.qpos[:] = 0
            d_.qpos[3] = 1.0
            d_.qpos[adr] = q
            mujoco.mj_kinematics(m_, d_)
        a = d.xanchor[jid_ours] - d.xpos[1]
        b = dr.xanchor[jid_theirs] - dr.xpos[1]
        worst = max(worst, float(np.abs(a - b).max()))
    assert worst < 1e-3
    assert abs(model.body_mass.sum() / ref.body_mass.sum() - 1) < 0.02


def test_stands_for_ten_seconds_on_the_flat_floor():
    from motion2robot.robot.world import make_world

    robot = load_robot("op3")
    m = make_world(robot, "flat")
    d = mujoco.MjData(m)
    d.qpos[:] = robot.nominal_qpos
    d.qpos[2] += 0.01  # dropped from 1 cm
    d.ctrl[:] = d.qpos[m.jnt_qposadr[m.actuator_trnid[:, 0]]]
    mujoco.mj_forward(m, d)
    torso = robot.torso_body
    z0 = d.xpos[torso, 2]
    lowest, max_tilt = z0, 0.0
    while d.time < 10.0:
        mujoco.mj_step(m, d)
        lowest = min(lowest, d.xpos[torso, 2])
        max_tilt = max(max_tilt, float(np.degrees(np.arccos(np.clip(d.xmat[torso, 8], -1, 1)))))
    assert lowest > 0.8 * z0
    assert max_tilt < 20.0
    assert np.linalg.norm(d.qvel[:3]) < 0.01  # settled, not sliding

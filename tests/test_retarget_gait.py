"""The ``steps`` legs mode: the leg tracker, and real walks walked by the pattern (feet held,
lifted, balanced, smooth at a finer rate, placed where the human's feet stand and point)."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.motion import read_motion
from motion2robot.motion.ops import spline, trim
from motion2robot.retarget import RetargetOptions, retarget
from motion2robot.retarget.footholds import stance_width
from motion2robot.retarget.leg_tracker import LegTracker, _envelope_below
from motion2robot.robot import load_robot
from motion2robot.robot.chains import foot_ancestor_mask
from motion2robot.validate import CheckOptions, check
from tests._shared import MOTIONS, requires_shared


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def test_stance_width_keeps_op3_soles_apart(op3):
    width = stance_width(op3)
    sole_width = 2 * max(f.sole_half[1] for f in op3.config.feet)
    assert width >= sole_width + 0.01 - 1e-12


def test_envelope_stays_below_its_bound_and_is_smooth():
    t = np.arange(400) / 30.0
    bound = 0.25 - 0.02 * (np.sin(2 * np.pi * 1.3 * t) > 0.7)   # dips of 2 cm, sharp edges
    out = _envelope_below(bound, 12, 30.0)
    assert (out <= bound + 1e-4).all()
    acc = np.abs(np.diff(out, 2)) * 30.0 ** 2
    assert acc.max() < 0.5   # m/s^2: the sharp dips become gentle


def test_leg_tracker_reaches_the_robot_s_own_feet_and_com(op3):
    """Targets from a known posture: the tracker finds a posture whose sole corners and CoM are on
    them within 0.1 mm, starting from the nominal pose."""
    import mujoco

    q = np.asarray(op3.nominal_qpos, float).copy()
    tr = LegTracker(op3)
    q[tr.qadr] += np.random.default_rng(0).uniform(-0.15, 0.15, len(tr.qadr))
    q[tr.qadr] = np.clip(q[tr.qadr], tr.lo + 0.2, tr.hi - 0.2)
    d = mujoco.MjData(op3.model)
    d.qpos[:] = q
    mujoco.mj_kinematics(op3.model, d)
    mujoco.mj_comPos(op3.model, d)
    corners = d.site_xpos[np.asarray(op3.sole_sites)].reshape(1, 2, 4, 3).copy()
    com = d.subtree_com[op3.root_body, :2].reshape(1, 2).copy()
    start = np.asarray(op3.nominal_qpos, float)[None].copy()
    start[0, :3] = q[:3]
    out, err = tr.solve(start, corners, com, 30.0)
    assert err[0] < 1e-4


@requires_shared
def test_a_real_walk_is_walked_feet_held_lifted_and_balanced(op3):
    """The Bandai walk (trimmed) as steps at x2.5: every check passes (planted soles below 1 cm/s at
    every corner, swing feet clear, ZMP inside, torques, physics playback), the robot goes forward,
    and the 100 fps version shows no new spike."""
    human = trim(read_motion(MOTIONS / "bvh" / "bandai_walk_normal_001.bvh")[0], 0, 90)
    motion = retarget(human, op3, RetargetOptions(tempo=2.5, legs="steps"))
    report = check(motion, op3, CheckOptions())
    assert report.feasible, report.reasons
    walk = motion.meta["solver"]["steps"]
    assert walk["tracking_error_m"] < 0.005
    assert motion.qpos[-1, 0] - motion.qpos[0, 0] > 0.1   # it walks forward
    swing = np.asarray(motion.meta["contacts"], bool)
    assert (~swing).any(axis=0).all()                       # both feet step

    # smooth by construction: at 100 fps the root's jerk stays below 50 m/s^3 (its acceleration
    # does not jump where the support changes: the ZMP moves across a double support; a jump of
    # 1 m/s^2 in a frame is 100), and the legs' peak accelerations stay within 1.5x of the native rate's
    fine = retarget(human, op3, RetargetOptions(tempo=2.5, legs="steps", fps=100.0))
    acc = np.diff(fine.qpos, 2, axis=0) * fine.fps ** 2
    assert np.abs(np.diff(acc[:, :3], axis=0)).max() * fine.fps < 50.0   # m/s^3: no jump (was 83 in one frame)
    legs = 7 + np.flatnonzero(foot_ancestor_mask(op3).any(axis=1))
    native = np.abs(np.diff(motion.qpos[:, legs], 2, axis=0)).max() * motion.fps ** 2
    assert np.abs(acc[:, legs]).max() <= 1.5 * native


@requires_shared
def test_a_throw_that_pivots_is_stepped_with_the_arms_clear_of_the_new_legs(op3):
    """MDM's throw #8 pivots on its left foot while the right shuffles round it, and swings its
    arms past its hips: the shuffles are laid beside the standing foot (the tracker keeps every
    sole corner on its plan) and the free solve's arms, clear of the human's legs, are pushed clear
    of the regenerated ones (an elbow went 16 mm into a hip): the self-collision check passes."""
    human = read_motion(MOTIONS / "mdm_results" / "mdm_throw_ball_results.npy", clip=8)[0]
    motion = retarget(human, op3, RetargetOptions(tempo=1.0, legs="steps"))
    assert motion.meta["solver"]["steps"]["tracking_error_m"] < 0.005
    report = check(motion, op3, CheckOptions(physics=False))
    assert report.checks["self_collision"]["ok"], report.reasons
    assert report.checks["joint_limits"]["ok"], report.reasons


@requires_shared
def test_a_finer_rate_walks_the_native_schedule(op3):
    """A 20 fps GMD walk with a hop retargeted at 100 fps: its contacts are scheduled on the
    native frames (detected at 100 fps they flickered into a 0.05 s hop beside a flight phase:
    5.1x and 3.0x the native peak root and joint accelerations), and its swings last 12 native
    frames where the double supports leave room (with 8-frame swings the pelvis rose within
    0.15 s of each lift-off, a feature the 20 fps frames averaged down: 1.57x at 100 fps), so the
    100 fps result's peaks are within 1.5x of the native frames' second differences (measured
    1.29x and 1.04x) and of the spline through them."""
    human = read_motion(MOTIONS / "mdm_results" / "gmd_template_joints.npy")[0]
    assert human.fps == 20.0
    native = retarget(human, op3, RetargetOptions(tempo=1.0, legs="steps"))
    fine = retarget(human, op3, RetargetOptions(tempo=1.0, legs="steps", fps=100.0))

    def peaks(q, fps):
        acc = np.abs(np.diff(q, 2, axis=0)) * fps ** 2
        return acc[:, :3].max(), acc[:, 7:].max()

    (rn, jn), (rf, jf) = peaks(native.qpos, native.fps), peaks(fine.qpos, fine.fps)
    assert rf <= 1.5 * max(rn, 0.5) and jf <= 1.5 * max(jn, 5.0)
    between = spline(native.qpos, np.arange(fine.num_frames) * native.fps / fine.fps)
    (rs, js) = peaks(between, fine.fps)
    assert rf <= 1.5 * max(rs, 0.5) and jf <= 1.5 * max(js, 5.0)
    # the same schedule in seconds: each 100 fps frame's contacts are its nearest 20 fps frame's
    cn, cf = np.asarray(native.meta["contacts"], bool), np.asarray(fine.meta["contacts"], bool)
    nearest = np.clip(np.rint(np.arange(len(cf)) / 5.0).astype(int), 0, len(cn) - 1)
    assert (cf == cn[nearest]).mean() > 0.98


@requires_shared
def test_a_sliding_thrower_keeps_its_height_at_any_rate(op3):
    """MDM's throw #25 stands throughout while its feet slide: the walking pattern's root height
    comes from the free solve (the pelvis over feet on the floor), so the robot stands too, at
    the same height at 20 and 100 fps (from the pinned solve, whose soles were pinned at the
    sliding feet's placements, the root was dragged 9 cm below the floor in places and the
    robot crouched to 0.18 m at 20 fps and 0.20 m at 100, up to 38 mm apart)."""
    human = read_motion(MOTIONS / "mdm_results" / "mdm_throw_ball_results.npy", clip=25)[0]
    native = retarget(human, op3, RetargetOptions(tempo=1.0, legs="steps"))
    fine = retarget(human, op3, RetargetOptions(tempo=1.0, legs="steps", fps=100.0))
    z20 = native.qpos[:, 2]
    z100 = np.interp(np.arange(native.num_frames) / native.fps, np.arange(fine.num_frames) / fine.fps, fine.qpos[:, 2])
    assert z20.min() > 0.24 and z100.min() > 0.24
    assert np.abs(z20 - z100).max() < 0.01  # measured 6 mm: the single supports' rises differ


@requires_shared
def test_cli_legs_steps(tmp_path, capsys):
    src = MOTIONS / "bvh" / "bandai_walk-back_normal_001.bvh"
    out = tmp_path / "w.npz"
    code = main(["retarget", str(src), "--legs", "steps", "--tempo", "2.5", "-o", str(out)])
    text = capsys.readouterr().out
    assert out.exists() and code in (0, 1)
    assert "steps" in text


def test_swings_move_only_above_the_checks_swing_clearance(op3):
    """The swing shape of ``steps``: the foot is still (horizontally) until it is above the check's
    skimming clearance and again from where it comes back down to it, and it moves over more than
    the middle half of the swing (a shorter horizontal window peaks higher in the legs)."""
    from motion2robot.retarget.footsteps import APEX_RATIO, lift
    from motion2robot.retarget.gait import SWING_SHAPE
    from motion2robot.validate.options import SWING_CLEARANCE_RATIO

    lead, ramp = SWING_SHAPE
    clearance = SWING_CLEARANCE_RATIO / APEX_RATIO  # as a fraction of the apex
    assert lift(np.array([lead]), ramp)[0] > 1.2 * clearance
    assert lift(np.array([1.0 - lead]), ramp)[0] > 1.2 * clearance
    assert 1.0 - 2.0 * lead > 0.5


@pytest.mark.slow
@requires_shared
def test_g1_walks_a_real_walk_with_its_feet_on_the_plan(monkeypatch):
    """On the G1 (menagerie) the pattern's targets are reached in every frame of a real walk: the
    upper body comes from the free solve, whose arms and waist move at human rates (the pinned
    solve's jerked at up to 2,400 rad/s^2 and the CoM plan following them lost the feet), and the
    result passes the kinematic checks of the feet and joints."""
    from tests._shared import MENAGERIE

    if MENAGERIE is None:
        pytest.skip("no menagerie root")
    monkeypatch.setenv("MENAGERIE_ROOT", str(MENAGERIE))
    load_robot.cache_clear()
    try:
        g1 = load_robot("menagerie:unitree_g1")
        human = read_motion(MOTIONS / "bvh" / "bandai_walk_normal_001.bvh")[0]
        motion = retarget(human, g1, RetargetOptions(legs="steps", tempo="1"))
    finally:
        load_robot.cache_clear()
    walk = motion.meta["solver"]["steps"]
    assert walk["tracking_error_m"] < 1e-3
    assert walk["path_m"] > 1.0
    upper = np.flatnonzero(~foot_ancestor_mask(g1).any(axis=1))
    acc = np.abs(np.diff(motion.qpos[:, 7 + upper], 2, axis=0)).max() * motion.fps ** 2
    assert acc < 400.0, acc
    c = check(motion, g1, CheckOptions(physics=False)).checks
    assert c["joint_limits"]["ok"] and c["velocity_limits"]["ok"] and c["ground"]["ok"], c["ground"]


@requires_shared
def test_without_smoothing_the_pattern_keeps_the_free_solve_s_upper_body_within_the_speed_limit(op3):
    """``smoothing=False`` (the projection's first phase cuts it, as for the whole body): the upper
    body and head are the free solve's, under the exact velocity clamp only, not low-passed and
    rounded off to the servos' targets (on the GMD walk: up to 2.7 mrad from the smoothed ones,
    every frame the free solve's own)."""
    from dataclasses import replace

    from motion2robot.retarget.gait import footing, steps

    human = read_motion(MOTIONS / "bvh" / "gen_gmd_ik_anim0.bvh")[0]
    opts = RetargetOptions(tempo=1.0, legs="steps")
    smooth = steps(human, op3, opts)
    first = footing(human, op3, replace(opts, smoothing=False))
    raw = steps(human, op3, replace(opts, smoothing=False), first)
    upper = 7 + np.flatnonzero(~foot_ancestor_mask(op3).any(axis=1))
    assert np.abs(raw.qpos[:, upper] - smooth.qpos[:, upper]).max() > 1e-3
    speed = np.abs(np.diff(raw.qpos[:, upper], axis=0)) * raw.fps
    assert (speed <= op3.velocity_limit[upper - 7] + 1e-9).all()
    # the free solve's own hinges where the clamp leaves them (the arms pushed clear of the legs aside)
    near = np.abs(raw.qpos[:, upper] - first.Q[:, upper])
    assert np.median(near) < 1e-9


@requires_shared
def test_a_slowed_clip_is_scheduled_on_its_own_frames(op3):
    """At x1.6 the schedule is made on the clip's own frames (every 1.6 frames of the slowed
    motion) and each slowed frame takes its nearest own frame's labels, so its phase edges are
    edges a motion at the clip's own frames can carry (a projected ``human'``'s contacts)."""
    from motion2robot.retarget.gait import footing
    from motion2robot.retarget.tempo import stretch

    human = read_motion(MOTIONS / "bvh" / "gen_gmd_ik_anim0.bvh")[0]
    labels = footing(stretch(human, 1.6), op3, RetargetOptions()).setup.labels
    own = np.rint(np.arange(len(labels)) / 1.6).astype(int)
    for i in np.unique(own):
        assert (labels[own == i] == labels[own == i][0]).all()
    assert (~labels).any(axis=0).all()   # both feet step

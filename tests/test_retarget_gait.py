"""The ``steps`` legs mode: footholds re-laid within the robot's reach, the leg tracker, and a real
walk walked by the pattern (feet held, lifted, balanced, smooth at a finer rate)."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.motion import read_motion
from motion2robot.motion.ops import spline, trim
from motion2robot.retarget import RetargetOptions, retarget
from motion2robot.retarget.footholds import grounded, shorten_steps, stance_width, step_factor, widen_swings
from motion2robot.retarget.leg_tracker import LegTracker, _envelope_below
from motion2robot.robot import load_robot
from motion2robot.robot.chains import foot_ancestor_mask
from motion2robot.validate import CheckOptions, check
from tests._shared import MOTIONS, requires_shared


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def _sole(x, y, yaw=0.0, half=(0.06, 0.04)):
    c, s = np.cos(yaw), np.sin(yaw)
    local = np.array([[half[0], half[1]], [half[0], -half[1]], [-half[0], -half[1]], [-half[0], half[1]]])
    xy = local @ np.array([[c, s], [-s, c]]) + [x, y]
    return np.concatenate([xy, np.zeros((4, 1))], axis=1)


def _walk(stride=0.4, n=4, width=0.04, yaws=None):
    """Placements of a straight walk along +x: alternating feet, each phase 10 frames with 5 frames
    of swing between a foot's phases; both feet down for the first 10 frames."""
    T = 10 + 10 * n + 10
    soles = np.full((T, 2, 4, 3), np.nan)
    labels = np.zeros((T, 2), bool)
    soles[:10, 0], soles[:10, 1] = _sole(0.0, width / 2), _sole(0.0, -width / 2)
    labels[:10] = True
    for i in range(n):
        f = i % 2
        a = 10 + 10 * i
        x = (i + 1) * stride / 2
        yaw = 0.0 if yaws is None else yaws[i]
        prev = np.flatnonzero(labels[:a, f])[-1]
        labels[prev + 1:a + 5, f] = False
        soles[a + 5:a + 20, f] = _sole(x, (width / 2) * (1 if f == 0 else -1), yaw)
        labels[a + 5:a + 20, f] = True
    labels[:, :][np.isnan(soles[..., 0, 0])] = False
    return soles, labels


def _centres(soles, labels):
    from motion2robot.retarget.contacts import phases

    return [(f, a, soles[a, f].mean(axis=0)[:2]) for f, a, b in sorted(phases(labels), key=lambda r: r[1])]


def test_steps_are_shortened_to_the_reach_and_the_feet_kept_a_stance_width_apart():
    soles, labels = _walk(stride=0.4, width=0.04)
    k = step_factor(soles, labels, 0.05)
    assert k == pytest.approx(0.05 / 0.2)  # steps of 0.2 m between the feet
    out = shorten_steps(soles, labels, k, width=0.09, max_turn=0.35)
    laid = _centres(out, labels)
    for (f0, _, c0), (f1, _, c1) in zip(laid[1:], laid[2:]):
        if f0 != f1:
            assert abs(c1[0] - c0[0]) == pytest.approx(0.05, abs=1e-9)   # shortened
            assert abs(c1[1] - c0[1]) == pytest.approx(0.09, abs=1e-9)   # a stance width apart
    yaw = [np.arctan2(*(o[0, :2] + o[1, :2] - o[2, :2] - o[3, :2])[::-1]) for o in out[labels[:, 0], 0]]
    assert np.allclose(yaw, 0.0)  # straight walk: the feet still point ahead


def test_a_wide_side_step_shrinks_like_a_long_one():
    """Feet 0.3 m apart sideways (a thrower's side step): what lies beyond the robot's stance
    width shrinks by the step factor, as a step's length does; a narrower human stance still
    lands a stance width apart."""
    soles, labels = _walk(stride=0.4, width=0.3)
    out = shorten_steps(soles, labels, 0.25, width=0.09, max_turn=0.35)
    laid = _centres(out, labels)
    for (f0, _, c0), (f1, _, c1) in zip(laid[1:], laid[2:]):
        if f0 != f1:
            assert abs(c1[1] - c0[1]) == pytest.approx(0.09 + 0.25 * (0.3 - 0.09), abs=1e-9)


def test_turns_are_kept_within_what_the_hips_can_twist():
    soles, labels = _walk(yaws=[0.8, 0.8, 1.6, 1.6])  # the human turns 0.8 rad per step pair
    out = shorten_steps(soles, labels, 0.5, width=0.09, max_turn=0.35)
    laid = [(f, a) for f, a, _ in _centres(out, labels)]

    def yaw(f, a):
        s = out[a, f]
        return np.arctan2(*(s[0, :2] + s[1, :2] - s[2, :2] - s[3, :2])[::-1])

    for (f0, a0), (f1, a1) in zip(laid, laid[1:]):
        if a1 > a0:
            assert abs(yaw(f1, a1) - yaw(f0, a0)) <= 0.35 + 1e-9
    assert yaw(*laid[-1]) > 0.6  # the heading is caught up over the steps


def test_a_foot_turns_no_faster_than_its_swing_allows():
    """The same turning walk with a turn rate: each foot's own yaw changes from its last placement
    by at most the rate times its swing's frames (5 here), and the heading still comes round."""
    soles, labels = _walk(n=12, yaws=[0.8, 0.8] + [1.6] * 10)
    rate = 0.04  # rad per frame: 0.2 rad per 5-frame swing
    out = shorten_steps(soles, labels, 0.5, width=0.09, max_turn=0.35, turn_rate=rate)
    free = shorten_steps(soles, labels, 0.5, width=0.09, max_turn=0.35)

    def yaw(o, f, a):
        s = o[a, f]
        return np.arctan2(*(s[0, :2] + s[1, :2] - s[2, :2] - s[3, :2])[::-1])

    def turns(o):  # (own turn, swing frames) of every step
        for f in range(2):
            starts = [a for g, a, _ in _centres(o, labels) if g == f]
            for a0, a1 in zip(starts, starts[1:]):
                yield abs(yaw(o, f, a1) - yaw(o, f, a0)), a1 - 1 - np.flatnonzero(labels[:a1, f])[-1]

    assert all(turn <= rate * swing + 1e-9 for turn, swing in turns(out))
    assert max(turn for turn, _ in turns(free)) > 0.25  # without the rate, steps turn farther
    assert yaw(out, *[(f, a) for f, a, _ in _centres(out, labels)][-1]) > 1.4  # caught up


def test_a_foot_stepping_twice_in_a_row_stays_beside_the_one_it_stands_on():
    """The right foot shuffles three times, turning 0.35 rad and moving 8 cm inwards each time,
    while the left stands (an MDM throw's pivot): laid from its own last placement it turned
    1.3 rad from the left foot, which no pair of hip yaws reaches (the leg tracker lost the feet).
    Each placement is laid from the left foot: within max_turn of it, a stance width to its side."""
    T = 60
    soles = np.full((T, 2, 4, 3), np.nan)
    labels = np.zeros((T, 2), bool)
    soles[:, 0] = _sole(0.0, 0.05)
    labels[:, 0] = True
    for i, a in enumerate(range(0, T, 15)):
        soles[a:a + 10, 1] = _sole(0.0, -0.05 + 0.08 * i, -0.35 * i)
        labels[a:a + 10, 1] = True
    out = shorten_steps(soles, labels, 0.5, width=0.09, max_turn=0.35)

    def yaw(s):
        return np.arctan2(*(s[0, :2] + s[1, :2] - s[2, :2] - s[3, :2])[::-1])

    left = out[0, 0]
    for a in range(15, T, 15):
        right = out[a, 1]
        assert abs(yaw(right) - yaw(left)) <= 0.35 + 1e-9
        assert left.mean(axis=0)[1] - right.mean(axis=0)[1] >= 0.09 - 1e-9   # to the left foot's right
    assert abs(yaw(out[45, 1]) - yaw(out[30, 1])) < 1e-9   # held at the hips' reach, not drifting on


def test_every_lift_off_waits_for_a_double_support():
    labels = np.zeros((40, 2), bool)
    labels[:10, 0] = True      # left down, then flight 10-15, right lands at 15
    labels[15:30, 1] = True    # right down 15-29, left lands at 30 as right lifts: no double support
    labels[30:40, 0] = True
    out = grounded(labels, fps=20.0, overlap_s=0.1, min_swing_s=0.1)
    assert out.any(axis=1).all()
    assert out[10:17, 0].all() and not out[17:30, 0].any()   # left stays until right lands + 2 frames
    assert out[15:32, 1].all() and not out[32:, 1].any()     # right lifts 2 frames after left lands
    jump = np.zeros((30, 2), bool)
    jump[:10], jump[16:] = True, True                          # both feet leave at 10, land at 16
    out = grounded(jump, fps=20.0, overlap_s=0.1, min_swing_s=0.1)
    assert out.any(axis=1).all() and out[10:18].any(axis=1).all()
    near = np.zeros((40, 2), bool)
    near[:20, 0], near[21:40, 0], near[:40, 1] = True, True, False
    near[:3, 1] = True
    assert (grounded(near, 20.0, 0.1, 0.1)[20] == near[20]).all()  # no landing to wait for: unchanged


def test_a_swing_beside_a_flight_is_widened_once_the_flight_is_grounded():
    """At 100 fps: the right foot down, a flight, the left lands and hops 5 frames, lands again,
    another flight, the right lands. Widening alone finds no room for the hop (the right foot is
    in the air around it); once the flights are grounded it does, and the double support before
    each lift-off is given back."""
    from motion2robot.retarget.footholds import walking_labels
    from motion2robot.retarget.contacts import phases

    labels = np.zeros((120, 2), bool)
    labels[:26, 1] = labels[90:, 1] = True
    labels[43:54, 0] = labels[59:81, 0] = True
    out = walking_labels(labels, 100.0, 0.2, 0.2)
    runs = sorted(phases(out), key=lambda r: r[1])
    for f, a, b in runs:
        later = [r for r in runs if r[0] == f and r[1] > a]
        if later:
            assert later[0][1] - b >= 19                       # the swing: 5 frames before
            assert out[b - 1, 1 - f] and out[b, 1 - f]           # lifts off from a double support


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


def _row(labels, f):
    return "".join(str(int(x)) for x in labels[:, f])


def test_short_swings_are_widened_into_the_double_supports_around_them():
    """A 2-frame swing becomes 6 frames, 2 taken from each side where the other foot is down; a
    swing next to the other foot's swing (no double support to take) keeps what it can get; a
    foot in the air at the clip's ends is not a swing; long swings are untouched."""
    left = "11111" "00" "11111" "111111" "111"
    right = "11111" "11" "11111" "000000" "111"
    labels = np.array([[a == "1", b == "1"] for a, b in zip(left, right)])
    out = widen_swings(labels, 6)
    assert _row(out, 0) == "111" "000000" "111111111111"
    assert _row(out, 1) == right  # its swing already lasts 6 frames
    # the other foot lifts right after: only the frames before can join the swing
    left2 = "11111" "00" "1" "111111"
    right2 = "11111" "11" "0" "000011"
    tight = np.array([[a == "1", b == "1"] for a, b in zip(left2, right2)])
    got = _row(widen_swings(tight, 6), 0)
    assert got == "1" "000000" "1111111"  # all four frames from before the swing
    edges = np.array([[False, True]] * 3 + [[True, True]] * 5 + [[False, True]] * 2)
    np.testing.assert_array_equal(widen_swings(edges, 6), edges)


def test_a_long_swing_is_sought_only_where_the_stances_keep_their_double_support():
    """Widening with ``keep``: a swing lengthens into its foot's contact phases only while they
    keep ``keep`` frames; quick footwork (3-frame stances between 8-frame swings, a tennis
    serve's) gives nothing and keeps its swings, where leaving 1 frame (``keep=1``) would shrink
    its stances to a frame each."""
    left = "1111111111" "0000" "1111111111"
    right = "1" * 24
    labels = np.array([[a == "1", b == "1"] for a, b in zip(left, right)])
    assert _row(widen_swings(labels, 8, keep=4), 0) == "1" * 8 + "0" * 8 + "1" * 8
    assert _row(widen_swings(labels, 20, keep=4), 0) == "1111" + "0" * 16 + "1111"  # 4 frames kept each side
    quick = "1111" "00000000" "111" "00000000" "1111"
    other = "1" * len(quick)
    labels = np.array([[a == "1", b == "1"] for a, b in zip(quick, other)])
    assert _row(widen_swings(labels, 12, keep=4), 0) == quick
    assert _row(widen_swings(labels, 12), 0).count("1") < quick.count("1")


def test_grounding_gives_way_to_a_long_swing_not_to_a_flight():
    """``grounded`` with ``keep_swing_s``: a lift-off right after the other foot lands waits for
    the double support only as far as the swing keeps its length (a 12-frame swing keeps 12, the
    double support shrinks to what is left, at least a frame); a foot lifting with the other in
    the air still waits for the landing."""
    # right lands at 10; left lifts at 11 for a 12-frame swing, then both down
    left = "1" * 11 + "0" * 12 + "1" * 7
    right = "1" * 5 + "0" * 5 + "1" * 20
    labels = np.array([[a == "1", b == "1"] for a, b in zip(left, right)])
    old = grounded(labels, 20.0, 0.2, 0.4)                    # 4 frames of double support: the swing 9
    assert _row(old, 0) == "1" * 14 + "0" * 9 + "1" * 7
    kept = grounded(labels, 20.0, 0.2, 0.4, keep_swing_s=0.6)
    assert _row(kept, 0) == left                               # the swing keeps its 12 frames
    # the left foot lifts while the right is still in the air: it waits for the landing
    early = np.array([[a == "1", b == "1"] for a, b in zip("1" * 7 + "0" * 16 + "1" * 7, right)])
    assert _row(grounded(early, 20.0, 0.2, 0.4, keep_swing_s=0.6), 0).startswith("1" * 11)

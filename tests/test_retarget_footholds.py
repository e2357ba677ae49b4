"""Footholds of the walking pattern (:mod:`motion2robot.retarget.footholds`): placements, steps
shortened and turned within the robot's reach, the contact schedule."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.retarget.footholds import grounded, shorten_steps, step_factor, widen_swings
from tests._shared import MOTIONS, requires_shared


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
    Each placement is laid from the left foot: within max_turn of it, a stance width to its side
    (in the step's heading)."""
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
        h = 0.5 * (yaw(left) + yaw(right))  # the step's heading: midway between the two feet
        side = np.array([-np.sin(h), np.cos(h)])
        assert (left.mean(axis=0)[:2] - right.mean(axis=0)[:2]) @ side >= 0.09 - 1e-9   # to the left foot's right
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


def test_placements_are_where_the_human_s_feet_stand_and_point():
    """``feet_placements``: per contact phase, the robot's ankle->toe keypoints point along the
    human's ankle->toe direction (over the frames the human's foot is down: the sole turned by the
    keypoints' own angle to it) and its centre is the ankle where it lands plus the robot's
    ankle->sole-centre offset turned to the sole's heading; a frame of the phase in which the
    human's foot is not down (a schedule's widened stance) does not move it."""
    from motion2robot.retarget.footholds import feet_placements

    T = 20
    labels = np.zeros((T, 2), bool)
    labels[2:12, 0] = True
    labels[:, 1] = True
    own = labels.copy()
    own[10:12, 0] = False                          # the human's left foot already lifting
    ankles = np.zeros((T, 2, 2))
    ankles[:, 0] = [0.3, 0.1]
    ankles[3:10, 0] += [0.002, 0.0]                 # it slides a little after landing
    ankles[10:12, 0] = [0.9, 0.4]                   # ... far from where it stood
    ankles[:, 1] = [0.0, -0.1]
    yaw = 0.4
    toes = ankles + 0.05 * np.array([np.cos(yaw), np.sin(yaw)])
    toes[:, 1] = ankles[:, 1] + [0.05, 0.0]         # the right foot points ahead
    soles = np.full((T, 2, 4, 3), np.nan)
    soles[labels[:, 0], 0] = _sole(0.31, 0.09, 0.1)   # an unpinned solve's: another place and heading
    soles[:, 1] = _sole(0.01, -0.12, -0.2)
    offsets = np.array([[0.01, 0.0], [0.01, 0.0]])  # the sole's centre 1 cm ahead of the ankle
    turns = np.array([0.1, -0.1])                   # the robot's toe keypoints 0.1 rad outwards
    out = feet_placements(soles, labels, own, ankles, toes, offsets, turns)
    yaw -= 0.1                                      # so its sole turns 0.1 rad less than the human's foot

    left = out[2:12, 0]
    assert np.allclose(left, left[0])                                  # one placement for the phase
    centre = left[0].mean(axis=0)
    np.testing.assert_allclose(centre[:2], [0.3 + 0.01 * np.cos(yaw), 0.1 + 0.01 * np.sin(yaw)], atol=1e-12)
    assert centre[2] == 0.0
    fwd = left[0, 0, :2] + left[0, 1, :2] - left[0, 2, :2] - left[0, 3, :2]
    assert np.arctan2(fwd[1], fwd[0]) == pytest.approx(yaw)
    np.testing.assert_allclose(np.ptp(left[0, :, :2], axis=0).max(), np.ptp(soles[2, 0, :, :2], axis=0).max(),
                               atol=0.02)                             # the sole's own layout
    np.testing.assert_allclose(out[0, 1].mean(axis=0)[:2], [0.01 * np.cos(0.1), -0.1 + 0.01 * np.sin(0.1)],
                               atol=1e-12)
    assert np.isnan(out[0, 0]).all()                                   # no contact, no placement


def test_steps_are_laid_in_the_heading_between_the_feet():
    """A straight walk with the left foot turned out 0.3 rad and the right straight (the CMU walk's
    feet): each step is measured and laid in the heading midway between the foot it steps from and
    its own, so the longest step, laid, is the reach in that heading (measured in the standing
    foot's heading alone, a step from the turned-out foot went sideways by its toe-out)."""
    soles, labels = _walk(stride=0.4, n=6, width=0.09, yaws=[0.3, 0.0] * 3)
    soles[:10, 0] = _sole(0.0, 0.045, 0.3)
    soles[:10, 1] = _sole(0.0, -0.045, 0.0)
    k = step_factor(soles, labels, 0.05)
    out = shorten_steps(soles, labels, k, width=0.09, max_turn=0.35)
    laid = _centres(out, labels)
    heading = 0.15
    fwd = np.array([np.cos(heading), np.sin(heading)])
    fore = [abs(float((c1 - c0) @ fwd)) for (f0, _, c0), (f1, _, c1) in zip(laid[1:], laid[2:]) if f0 != f1]
    assert max(fore) == pytest.approx(0.05, abs=1e-9)


def test_the_start_is_a_stance_the_robot_reaches():
    """A clip cut mid-stride starts with the feet a stride apart: they stand about their midpoint
    a shortened step apart (the step factor counts it), at least a stance width apart sideways."""
    soles, labels = _walk(stride=0.4, n=4, width=0.04)
    soles[:10, 0] = _sole(0.15, 0.02)
    soles[:10, 1] = _sole(-0.15, -0.02)
    labels[:10] = True
    k = step_factor(soles, labels, 0.05)
    assert k <= 0.05 / 0.3 + 1e-12           # the start's 0.3 m counts as a step
    out = shorten_steps(soles, labels, k, width=0.09, max_turn=0.35)
    left, right = out[0, 0].mean(axis=0)[:2], out[0, 1].mean(axis=0)[:2]
    np.testing.assert_allclose(left - right, [k * 0.3, 0.09], atol=1e-9)
    np.testing.assert_allclose(0.5 * (left + right), [0.0, 0.0], atol=1e-9)


@requires_shared
@pytest.mark.parametrize("clip", ["gmd_template_joints.npy", "012314.npy"])
def test_the_walking_schedule_is_its_own_schedule(clip):
    """Real clips whose schedule two rounds of widening and grounding left changing (by 3-11
    frames on these): run to its fixed point, the schedule scheduled again is itself, so a motion
    walked on it (``human'`` of a ``steps`` result) is walked on the same one."""
    from motion2robot.motion import read_motion
    from motion2robot.retarget.contacts import contact_labels, planted
    from motion2robot.retarget.footholds import walking_labels
    from motion2robot.retarget.gait import LONG_SWING_FRAMES, MIN_SWING_FRAMES, MIN_SWING_S, OVERLAP_S

    found = sorted(MOTIONS.rglob(clip))
    human = read_motion(found[0])[0]
    labels = planted(contact_labels(human)[0], human)
    fps = human.fps
    args = (fps, OVERLAP_S, max(MIN_SWING_S, MIN_SWING_FRAMES / fps), LONG_SWING_FRAMES / fps)
    once = walking_labels(labels, *args)
    assert not np.array_equal(once, labels)
    np.testing.assert_array_equal(walking_labels(once, *args), once)


def test_steps_just_over_the_reach_are_kept_with_a_slack():
    """A walk whose longest step is 3 % over the reach (a pattern's own placements, the feet
    pushed apart where they would meet) keeps its steps with a 5 % slack; one 10 % over is
    shortened to the reach as without it."""
    soles, labels = _walk(stride=0.4, width=0.04)             # steps of 0.2 m
    assert step_factor(soles, labels, 0.2 / 1.03) == pytest.approx(1 / 1.03)
    assert step_factor(soles, labels, 0.2 / 1.03, slack=0.05) == 1.0
    assert step_factor(soles, labels, 0.2 / 1.1, slack=0.05) == pytest.approx(1 / 1.1)

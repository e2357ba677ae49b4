"""The correction rounds of ``project`` (what runs when the exact reach cannot: a fixed tempo or
legs, another rate, ``reach`` off), on a real clip."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.motion.human import KP, SMPL22
from motion2robot.projection import (
    TOLERANCE,
    attenuation,
    chosen_solve,
    hinge_rms,
    project,
    refine,
    robot_points,
)
from motion2robot.retarget.scale import Scale, scaled_keypoints
from tests._projected import CLIP, clip_projection, direct_gap, op3, solved
from tests._shared import MOTIONS, requires_shared


@requires_shared
def test_the_correction_aims_the_solves_first() -> None:
    """The first phase corrects against the retargeting cut after its solves (no servo rounds,
    smoothing, ZMP stage or root pass); the second against the whole retargeting starts where the
    first ended. On an MDM throw retargeted on the stance the whole retargeting comes back within
    0.0004 rad (measured; 0.0042 with the rounds against the whole retargeting alone): the later
    stages pass on a motion they already made almost unchanged, but their thresholds switch on
    at a solve's small errors, which the rounds cannot aim through."""
    from motion2robot.motion import read_motion
    from motion2robot.projection import solver_stages
    from motion2robot.retarget import RetargetOptions, retarget

    robot = op3()
    cut = retarget(read_motion(MOTIONS / CLIP)[0], robot, solver_stages(RetargetOptions(tempo=1.0, legs="whole")))
    figs = cut.meta["solver"]
    assert figs["correction_rounds"] == 0 and figs["smoothing"] is None
    assert figs["dynamic_balance"] is None and figs["root_pass"] is None
    human = read_motion(MOTIONS / "mdm_results" / "mdm_throw_ball_results.npy", clip=3)[0]
    p = project(human, robot, options=solved())
    assert p.robot_motion.meta["fallback"]["mode"] == "stance" and not p.reached
    assert p.solver_rounds[0] > 0.05 and min(p.solver_rounds) < 0.001  # the solves' own gap, aimed away
    assert p.idempotence_rms <= TOLERANCE and len(p.rounds) == 1  # the whole retargeting agrees at once
    model = attenuation(p.robot_motion, robot, solved())
    _, only_whole = refine(p.direct, p.robot_motion, robot, chosen_solve(p.robot_motion, robot, solved()),
                           aim=model.aim)
    assert p.idempotence_rms < min(only_whole) / 4


@requires_shared
def test_a_walk_on_steps_is_corrected_through_the_steps_pattern() -> None:
    """A GMD walk goes on ``steps``: its human' is corrected against the ``steps`` pattern that
    made the robot motion (against the whole body its rounds stalled at 0.043 rad), so the default
    retargeting of human' walks the same footsteps again (measured 0.0002 rad; 0.0019 while the
    pattern laid the unpinned solve's soles, which follow a foot's heading at 5 %; 0.005 with
    plain rounds, 0.033 against the whole body). human' carries the schedule the pattern walked,
    which the pattern schedules the same, and its feet are placed where the robot's stood."""
    from motion2robot.motion import read_motion
    from motion2robot.retarget import RetargetOptions, retarget_and_check
    from motion2robot.retarget.contacts import phases, sole_yaw
    from motion2robot.retarget.gait import footing

    robot = op3()
    human = read_motion(MOTIONS / "bvh" / "gen_gmd_ik_anim0.bvh")[0]
    p = project(human, robot, options=solved())
    assert p.robot_motion.meta["fallback"]["mode"] == "steps"
    schedule = np.asarray(p.robot_motion.meta["schedule"], bool)
    np.testing.assert_array_equal(p.human.contacts, schedule)
    again, report = retarget_and_check(p.human, robot, solved())
    assert report.feasible and again.meta["fallback"]["mode"] == "steps"
    np.testing.assert_array_equal(np.asarray(again.meta["schedule"], bool), schedule)
    rms = hinge_rms(p.robot_motion, again)
    assert rms <= TOLERANCE and rms < direct_gap(p, solved()) / 30
    # the robot's feet mapped back (no correction) are placed where the robot's soles stood
    # (measured within 1.4 mm and 1e-6 rad; the toe keypoint's own 0.18 rad was 0.18 rad off)
    back = footing(p.direct.with_(contacts=schedule), robot, RetargetOptions())
    soles = back.setup.points(p.robot_motion.qpos)[1]
    for f, a, _ in phases(schedule):
        assert np.linalg.norm(back.placed[a, f].mean(axis=0)[:2] - soles[a, f].mean(axis=0)[:2]) < 0.002
        assert abs(sole_yaw(back.placed[a, f]) - sole_yaw(soles[a, f])) < 1e-3


@requires_shared
def test_the_correction_stops_when_its_rounds_stall() -> None:
    from motion2robot.projection.correction import STALL_ROUNDS, refine

    _, p = clip_projection()
    robot, q0 = op3(), p.robot_motion
    calls = []

    def stuck(h):  # a pipeline that misses by the same 0.02 rad whatever it is given
        calls.append(h)
        return q0.with_(qpos=np.concatenate([q0.qpos[:, :7], q0.qpos[:, 7:] + 0.02], axis=1))

    best, errors = refine(p.direct, q0, robot, stuck, rounds=16)
    assert len(calls) == len(errors) == STALL_ROUNDS + 1 and np.allclose(errors, 0.02)
    assert best is p.direct  # no round was better than the first


@requires_shared
def test_an_overshooting_round_is_retried_a_shorter_way() -> None:
    """A round that overshoots sends the next from the best ``human'`` half as far (with the
    damping raised, the step from the best is the same plain step, which overshot every round:
    an MDM throw spent 10 of its 16 rounds at the same gap); the next that improves goes the
    whole way again."""
    from motion2robot.projection.correction import REACH_SHRINK, refine

    _, p = clip_projection()
    robot, q0 = op3(), p.robot_motion
    calls = []

    def bumpy(h):  # 0.02 rad off at the start, 0.05 after a whole step, 0.01 after a shorter one
        calls.append(np.asarray(h.positions).copy())
        moved = np.abs(calls[-1] - calls[0]).max()
        full = np.abs(calls[1] - calls[0]).max() if len(calls) > 1 else np.inf
        off = 0.02 if len(calls) == 1 else (0.05 if moved > 0.75 * full else 0.01)
        return q0.with_(qpos=np.concatenate([q0.qpos[:, :7], q0.qpos[:, 7:] + off], axis=1))

    _, errors = refine(p.direct, q0, robot, bumpy, rounds=3, aim=lambda q, mu: q0)
    assert errors == pytest.approx((0.02, 0.05, 0.01))
    step = [np.abs(c - calls[0]).max() for c in calls[1:]]
    assert step[1] == pytest.approx(REACH_SHRINK * step[0])


@requires_shared
def test_the_rounds_keep_the_bones_of_the_direct_mapping(monkeypatch) -> None:
    """Rounds lured into stretching ``human'``'s legs (free, they stretched a HumanML3D clip's
    legs to 3.8 m and arms by 43 %, their retargeting ever nearer) move the bones' directions
    only: every round's lengths stay within BONE_SLACK of the direct mapping's, frame by frame."""
    import motion2robot.projection.correction as correction
    from motion2robot.projection.correction import BONE_SLACK, refine
    from motion2robot.projection.maths import bone_drift
    from motion2robot.retarget.scale import human_length

    _, p = clip_projection()
    robot, q0 = op3(), p.robot_motion
    legs0 = human_length(p.direct, "legs")
    below = [KP[k] for k in ("left_knee", "right_knee", "left_ankle", "right_ankle", "left_foot", "right_foot")]
    seen = []

    def way_back(motion, robot, h):  # the aim maps back to h with legs 20 % longer, anything else to h
        pos = np.array(h.positions)
        if motion.meta.get("aimed"):
            for side in ("left", "right"):
                hip = pos[:, [KP[f"{side}_hip"]]]
                idx = [j for j in below if SMPL22[j].startswith(side)]
                pos[:, idx] = hip + 1.2 * (pos[:, idx] - hip)
        return h.with_(positions=pos)

    def lured(h):  # 0.02 rad off, less the longer the legs
        seen.append(h)
        off = 0.02 / (1.0 + 50.0 * max(0.0, human_length(h, "legs") / legs0 - 1.0))
        return q0.with_(qpos=np.concatenate([q0.qpos[:, :7], q0.qpos[:, 7:] + off], axis=1))

    monkeypatch.setattr(correction, "project_motion", way_back)
    best, errors = refine(p.direct, q0, robot, lured, rounds=6, aim=lambda q, mu: q0.with_(meta={"aimed": True}))
    assert len(seen) > 2
    assert all(bone_drift(h.positions, p.direct.positions) <= BONE_SLACK + 1e-9 for h in seen)
    # the legs went as far as the slack lets them (the lure worked within it), no farther
    assert human_length(best, "legs") / legs0 - 1.0 == pytest.approx(BONE_SLACK, abs=1e-6)


@requires_shared
def test_the_correction_converges_at_a_slower_tempo() -> None:
    """At x2 the rounds compare human frame i with robot frame 2i (they compared frame i, and the
    rounds of every slowed clip drifted away: 0.046 -> 0.072 rad on a bow at x1.5), so human'
    retargeted at x2 comes back as close as at x1 (measured 0.0008 rad from 0.072; 0.0002 at x1)."""
    from motion2robot.motion import read_motion
    from motion2robot.retarget import RetargetOptions, retarget

    robot = op3()
    human = read_motion(MOTIONS / CLIP)[0]
    opts = RetargetOptions(tempo=2.0, legs="whole")
    p = project(human, robot, options=opts)
    again = retarget(p.human, robot, opts)
    rms = hinge_rms(p.robot_motion, again)
    assert hinge_rms(p.robot_motion, retarget(p.direct, robot, opts)) > 0.03 and rms < 2 * TOLERANCE
    assert rms == pytest.approx(min(p.rounds))  # what the rounds measured is what a user gets


@requires_shared
def test_direct_mapping_hits_the_robot_keypoints_at_the_slower_tempo() -> None:
    from motion2robot.motion import read_motion
    from motion2robot.retarget import RetargetOptions

    robot = op3()
    human = read_motion(MOTIONS / CLIP)[0]
    p = project(human, robot, options=RetargetOptions(tempo=2.0, legs="whole"), rounds=1)
    assert p.report is None and p.executable is None  # nothing judged at a fixed tempo and legs
    assert p.robot_motion.num_frames == 2 * (human.num_frames - 1) + 1 and p.human.num_frames == human.num_frames
    pts, mapped, _ = robot_points(p.robot_motion, robot)
    s = p.robot_motion.meta["scale"]
    scaled = scaled_keypoints(p.direct.positions, Scale(s["legs"], s["arms"], s["height"]))
    # human frame i is robot frame 2i: scaling human' back lands on the robot's keypoints exactly
    assert np.abs(scaled[:, mapped] - pts[::2][:, mapped]).max() < 1e-9
    assert p.human.contacts.shape == (human.num_frames, 2)
    assert np.array_equal(p.human.contacts, np.asarray(p.robot_motion.meta["contacts"], bool)[::2])

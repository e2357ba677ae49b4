"""The ``steps`` alternative: the human's footsteps walked by a walking pattern, the upper body as retargeted.

A whole-body retarget of a walk asks the robot for the human's stride and the human's balance
strategy (heel-toe roll, momentum carried over the stance foot); a flat-footed robot of position
servos can do neither, and the per-frame solve leaves acceleration spikes where the stance foot
changes. This pipeline keeps what the robot can take from the human (when each foot steps, where
it turns, the torso's heading, the arms and head) and regenerates the legs as a walking pattern,
smooth by construction (after Nakaoka et al., IJRR 2007: leg motion regenerated for the robot,
then a ZMP-based waist trajectory):

1. the whole-body pipeline's first stage, the free solve: where the human's feet go, the pelvis
   height with the feet on the floor, and the upper body tracking the human (the pinned solve of
   the whole-body pipeline is not run: pinning the soles at the human's placements, which the
   footholds below re-lay anyway, dragged the root of a sliding MDM thrower to 0.1 m below
   the floor, and its low-passed dips set a crouch that differed by 3-4 cm between 20 and 100
   fps);
2. footholds (:mod:`~.footholds`): a double support before every lift-off (runs and jumps are
   walked; a human walk's heel-up frames leave none), the human's placements (where its ankles
   stand and its feet point, :func:`placements`) re-laid step by step, each step
   shortened by one factor for the clip so the longest is STEP_REACH of the straight leg, the feet
   at the robot's own stance width, each foot turning no faster than TURN_SPEED of its hip's
   velocity limit allows over its swing; a foot stepping twice in a row laid from the one it
   stands beside; every swing at least MIN_SWING_FRAMES of the clip's own rate, and
   LONG_SWING_FRAMES where the foot's stances keep OVERLAP_S (the double support before the
   lift-off then shrinks rather than the swing), the whole schedule made on the clip's own frames
   at any output rate and tempo (:func:`native_walking_labels`);
   the contact plan's swings go straight between them, lifted
   (:mod:`~.footsteps`); a foot in the air at either end of the clip stands at its nearest placement;
3. the root: upright, facing where the feet do (:func:`feet_heading`), its height the free
   solve's low-passed and kept below what the legs reach (:func:`~.leg_tracker.root_height`);
   the hinges of the upper body and head: the free solve's, smoothed within the servos' limits
   (the pinned solve's upper body also answers for the human's full stride and static balance,
   which the pattern does not keep: on the G1 its arms and waist jerked at 400-2,400 rad/s^2
   where the free solve's move at 20-300, and the CoM plan following them lost the feet);
4. a CoM path between the feet whose cart-table ZMP stays inside every frame's shrunk support
   polygon (one QP over the clip: :func:`~.zmp_plan.cart_table_shift`);
5. per frame, the root and the leg hinges (:class:`~.leg_tracker.LegTracker`) with every sole
   corner on its plan and the CoM on its path: smooth targets give smooth joints;
6. the multi-body ZMP of the result (arms and swing legs included) measured and the CoM path
   shifted by the cart-table QP again, up to ZMP_ROUNDS tracking rounds in all;
7. the arms and head, clear of the human's legs in the free solve, pushed clear of the
   regenerated ones by themselves (:func:`~.solve_stages.free_limbs_clear`; an MDM thrower's elbow
   went 16 mm into a hip), within the servos' velocity and the joint limits.

What the robot does differs from the human in stride length and path (reported in
``meta["solver"]["steps"]``: the step factor, the stance width, the path covered); the policy of
:mod:`~.executable` says so in ``meta["fallback"]``. Units: metres, radians, seconds; world frame
z up; quaternions wxyz.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from motion2robot.motion.human import KP, HumanMotion
from motion2robot.motion.ops import resample
from motion2robot.retarget.constraints import clamp_velocity, support_margin, support_planes
from motion2robot.retarget.contact_plan import ContactPlan, plan_contacts
from motion2robot.retarget.contacts import anchor_soles, contact_labels, planted, sole_yaw, yaw_rotation
from motion2robot.retarget.footholds import (
    feet_placements,
    filled,
    shorten_steps,
    stance_width,
    step_factor,
    walking_labels,
)
from motion2robot.retarget.leg_tracker import LOST, LegTracker, root_height
from motion2robot.retarget.result import StageFigures, robot_motion
from motion2robot.retarget.setup import Setup, prepare
from motion2robot.retarget.smoothing import low_pass, smooth_hinges
from motion2robot.retarget.solve_stages import free_limbs_clear, free_solve
from motion2robot.retarget.zmp_plan import GRAVITY, MIN_SHIFT, cart_table_shift, multibody_zmp
from motion2robot.robot.chains import foot_ancestor_mask
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion

#: Hz, cutoff of the root's heading (a walk's per-step turns of the feet are averaged out).
ROOT_CUTOFF_HZ = 1.5
#: Hz, cutoff of the reference CoM path the balance QP stays near.
COM_CUTOFF_HZ = 1.0
#: The longest step (fore-aft distance between consecutive placements) as a fraction of the
#: straight leg's hip-to-sole distance; longer human steps are shortened to it (op3: 5 cm, where
#: the Bandai walk's scaled stride asks 0.22 m between the feet).
STEP_REACH = 0.18
#: Steps up to this fraction over STEP_REACH are walked as they are (step factor 1): the
#: pattern's own placements, the feet pushed apart where they would meet, measure up to 3 % over
#: (the Bandai run), so a motion walked on them was shortened again (its ``human'``, by 3 %:
#: 0.0016 rad from its robot motion where 0.0012 with the slack; the GMD walk 0.0009 -> 0.0001).
#: One dev clip's own steps fall in the band (a CMU jump, 2.7 % over; it goes on the stance).
STEP_SLACK = 0.05
#: rad a foot may turn from the one it steps from (op3's hip yaws reach 0.45 rad either way).
MAX_TURN = 0.35
#: Share of the legs' velocity limit a swing foot turns at (about its vertical), over the part of
#: the swing it moves in (:data:`SWING_SHAPE`): a foot turning 0.7 rad in a 0.2 s swing asked
#: op3's hip yaw for 6.7 rad/s, 1.4x its servo's, at every tempo (the swing stays 0.2 s; slowing
#: the clip lengthened the double supports).
TURN_SPEED = 0.5
#: s of double support before every lift-off (the human's flight phases and heel-up frames leave
#: none), and the least swing that is left (:func:`~.footholds.grounded`).
OVERLAP_S = 0.2
MIN_SWING_S = 0.2
#: The least swing in frames of the clip's own rate (a 20 fps clip: 0.4 s): a swing sampled by
#: fewer frames is a polygon of a few points to the servos, whose peaks a finer rate shows
#: (:func:`~.footholds.widen_swings` lengthens it into the double supports around it).
MIN_SWING_FRAMES = 8
#: The swing sought in frames of the clip's own rate where the foot's contact phases around it
#: keep a double support of OVERLAP_S (a 20 fps clip: 0.6 s): a 0.4 s swing's peaks fall between
#: 20 fps frames, and a 100 fps resampling showed them 1.5-1.7x taller on 12 clips.
LONG_SWING_FRAMES = 12
#: (lead, ramp) of the swings (:func:`~.footsteps.swing_path`): the foot rises over the first half
#: and sets down over the second (the whole-body plan's 0.3 lifts within 0.12 s of a 0.4 s swing,
#: a peak a 20 fps clip cannot show but a 100 fps one does), moving horizontally from a fifth in,
#: once it is 0.32 of its apex up (above ``check``'s swing clearance, a quarter of the apex, so it
#: never skims), to a fifth before touch-down: over 60 % of the swing, not the middle half, which
#: lowers the peak accelerations of the foot and the legs by about a third.
SWING_SHAPE = (0.2, 0.5)
#: s, weight of the CoM plan's jerk (:func:`~.zmp_plan.cart_table_shift`): the ZMP moves across
#: the double support instead of jumping.
JERK_TIME = 0.1
#: Rounds of (CoM plan, tracking); the second and later correct by the measured multi-body ZMP.
ZMP_ROUNDS = 3


@dataclass(frozen=True, eq=False)
class Footing:
    """Stage 1 of ``steps`` (:func:`footing`): the setup with the walking labels, the free solve
    ``Q`` (T, nq) with its solver stats and its sole corners (T, 2, 4, 3) m, the leg tracker, the
    longest step the legs take (m), the factor the human's steps shrink by to it, the human's
    placements (T, 2, 4, 3) (:func:`placements`) and the seconds it took (the setup, the solve)."""

    setup: Setup
    Q: np.ndarray
    free: object
    corners: np.ndarray
    tracker: LegTracker
    longest: float
    factor: float
    placed: np.ndarray
    prepare_s: float
    solve_s: float


def footing(human: HumanMotion, robot: Robot, options) -> Footing:
    """Stage 1 of ``steps`` on ``human`` at its own tempo, and the step factor: what the policy of
    :mod:`~.executable` reads to tell a walk from a glide before the pattern is made."""
    opt = replace(options, dynamic_balance=False)
    t0 = time.perf_counter()
    setup = prepare(human, robot, opt)
    # the clip's own frames (before any --fps resampling or tempo stretch; at a tempo k they come
    # every k/fps seconds of the slowed motion) sample every swing with MIN_SWING_FRAMES
    native = float(human.meta.get("resampled_from_fps") or human.fps) / float(human.meta.get("tempo") or 1.0)
    min_swing = max(MIN_SWING_S, MIN_SWING_FRAMES / native)
    labels, own = native_walking_labels(human, setup, native, min_swing, LONG_SWING_FRAMES / native)
    setup = replace(setup, labels=labels)
    t1 = time.perf_counter()
    Q, free = free_solve(setup)
    corners = setup.points(Q)[1]
    tracker = LegTracker(robot)
    longest = STEP_REACH * float(tracker.straight_reach().min())
    placed = placements(setup, anchor_soles(corners, setup.labels), own)
    k = step_factor(placed, setup.labels, longest, STEP_SLACK)
    return Footing(setup, Q, free, corners, tracker, longest, k, placed, t1 - t0, time.perf_counter() - t1)


def placements(setup: Setup, anchored: np.ndarray, own: np.ndarray) -> np.ndarray:
    """(T, 2, 4, 3) the human's placements in the walking labels' contact frames: from the human's
    own feet (:func:`~.footholds.feet_placements`: where its ankles stand, the robot's ankle and
    toe keypoints along its ankle->toe directions; ``own`` its planted frames) when the robot
    tracks both ankles and toes, else ``anchored`` (the unpinned solve's soles). Not the unpinned
    solve's soles alone: it follows a foot's heading weakly (op3, the Bandai walk: a toe target
    turned 0.1 rad turned the sole 0.005 rad), so the pattern laid the solve's compromise rather
    than where the human's feet pointed. The keypoints, not the sole's axis: the robot's feet
    mapped back onto the human (:mod:`~motion2robot.projection`) point where its keypoints do
    (op3: its toe site sits 0.18 rad outwards of the sole's axis, seen from the ankle), so the
    pattern lays them where they stood (and a person's feet, turned out 0.35 rad on the dev
    clips' median, are laid turned out by the rest)."""
    names = list(setup.problem.spec.kp_names)
    need = [f"{s}_{j}" for s in ("left", "right") for j in ("ankle", "foot")]
    if not all(n in names for n in need):
        return anchored
    kp0, corners0 = setup.points(setup.robot.nominal_qpos[None])[:2]
    offsets, turns = np.zeros((2, 2)), np.zeros(2)
    for f, side in enumerate(("left", "right")):
        yaw = float(sole_yaw(corners0[0, f]))
        local = yaw_rotation(-yaw)  # world -> sole frame
        ankle = kp0[0, names.index(f"{side}_ankle"), :2]
        offsets[f] = local @ (corners0[0, f, :, :2].mean(axis=0) - ankle)
        toe = local @ (kp0[0, names.index(f"{side}_foot"), :2] - ankle)
        turns[f] = np.arctan2(toe[1], toe[0])
    ankles = setup.kp[:, [KP["left_ankle"], KP["right_ankle"]], :2]
    toes = setup.kp[:, [KP["left_foot"], KP["right_foot"]], :2]
    return feet_placements(anchored, setup.labels, own, ankles, toes, offsets, turns)


def steps(human: HumanMotion, robot: Robot, options, first: Footing | None = None) -> RobotMotion:
    """The ``steps`` pipeline on ``human`` at its own tempo (see the module text); ``options``:
    the RetargetOptions of the whole-body stages it starts from; ``first``: its :func:`footing`
    when already made (by the policy's probe)."""
    f = first or footing(human, robot, options)
    t_rest = time.perf_counter()
    setup, Q, free, free_corners, tracker = f.setup, f.Q.copy(), f.free, f.corners, f.tracker
    longest, k = f.longest, f.factor
    width = stance_width(robot)
    legs = foot_ancestor_mask(robot).any(axis=1)
    turn_rate = TURN_SPEED * float(robot.velocity_limit[legs].min()) * (1.0 - 2.0 * SWING_SHAPE[0]) / setup.fps
    plan = plan_contacts(setup, free_corners, cap_swing_speed=False,
                         place=lambda soles, labels: shorten_steps(f.placed, labels, k, width, MAX_TURN, turn_rate),
                         swing_shape=SWING_SHAPE)
    Q, walked, figures = walk_pattern(setup, plan, Q, tracker)
    # the free solve's arms kept clear of the human's legs, not of the regenerated ones
    Q = free_limbs_clear(setup, walked.params(setup), Q)
    Q[:, 7:] = np.clip(clamp_velocity(Q[:, 7:], robot.velocity_limit, setup.fps), robot.lower, robot.upper)
    pts = setup.points(Q)
    solve_s = f.solve_s + time.perf_counter() - t_rest
    path = np.linalg.norm(np.diff(Q[:, :2], axis=0), axis=1).sum()
    human_path = np.linalg.norm(np.diff(setup.kp[:, 0, :2], axis=0), axis=1).sum()
    figures.update(step_factor=k, longest_step_m=longest, stance_width_m=width, path_m=float(path),
                   human_path_m=float(human_path))
    stages = StageFigures(free, None, 0, None, None, solve_s, f.prepare_s + solve_s)
    # the keypoint error is the posture's: the human moved along the robot's (shortened) path, as
    # the stance's is against the human held in place; the path itself is reported apart
    along = setup.kp.copy()
    along[..., :2] += (Q[:, :2] - setup.kp[:, 0, :2])[:, None, :]
    motion = robot_motion(replace(setup, kp=along), walked, Q, pts, stages, False)
    # the schedule the pattern walked, before a foot in the air at an end of the clip was stood at
    # its nearest placement (``contacts``): a human motion with these labels is scheduled the same
    return motion.with_(meta={**motion.meta, "human_root_xy": setup.kp[:, 0, :2].tolist(),
                              "schedule": setup.labels.astype(int).tolist(),
                              "solver": {**motion.meta["solver"], "steps": figures}})


def native_walking_labels(human: HumanMotion, setup: Setup, native: float, min_swing: float,
                          long_swing: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(T, 2) walking labels (:func:`~.footholds.walking_labels`) of ``human`` at its output rate,
    and the (T, 2) planted frames they were made from, both scheduled at the clip's ``native``
    rate: a clip resampled finer (``--fps``) or slowed down (its tempo stretch) has its contacts
    detected and its swings widened and grounded on the native frames, then each output frame
    takes the nearest native frame's, so every rate walks the same schedule in seconds (detected
    at 100 fps, a 20 fps GMD clip's contacts flickered into a 0.05 s hop beside a flight, and a
    60 fps CMU dance's into 0.04 s swings: 3-5x the native peaks) and places its feet from the
    same frames; and a slowed clip's schedule is one its own frames can carry (the contacts of its
    ``human'``, :mod:`~motion2robot.projection`, at the human's frames: scheduled on the slowed
    frames, their edges came back a frame off, 0.0013-0.0023 rad on 6 slowed walks and dances,
    0.0001-0.0017 since)."""
    if not setup.opt.contacts or abs(native - setup.fps) < 1e-9:
        return walking_labels(setup.labels, setup.fps, OVERLAP_S, min_swing, long_swing), setup.labels
    coarse = resample(human, native)
    own = planted(contact_labels(coarse)[0], coarse)
    labels = walking_labels(own, native, OVERLAP_S, min_swing, long_swing)
    nearest = np.clip(np.rint(np.arange(len(setup.labels)) * native / setup.fps).astype(int), 0, len(labels) - 1)
    return labels[nearest], own[nearest]


def feet_heading(corners: np.ndarray, fps: float) -> np.ndarray:
    """(T,) yaw (rad, unwrapped) between the two soles' headings (``corners`` (T, 2, 4, 3): front
    corners first), low-passed at ROOT_CUTOFF_HZ: the upright pelvis of a walking pattern faces
    where the feet do."""
    yaw = np.unwrap(sole_yaw(corners), axis=0)                                     # (T, 2)
    right = yaw[:, 1] + np.round((yaw[:, 0] - yaw[:, 1]) / (2 * np.pi)) * 2 * np.pi
    return low_pass(((yaw[:, 0] + right) / 2)[:, None], fps, ROOT_CUTOFF_HZ)[:, 0]


def walk_pattern(setup: Setup, plan: ContactPlan, Q: np.ndarray,
                 tracker: LegTracker) -> tuple[np.ndarray, ContactPlan, dict]:
    """Stages 3-6 of the module text on the free solve ``Q`` (whose root height, CoM height and
    upper-body and head hinges are kept) and the re-laid contact ``plan``, solved by
    ``tracker`` (the robot's): the trajectory, the plan it stands on (every foot planned in every
    frame) and figures."""
    robot, fps = setup.robot, setup.fps
    corners, contact = filled(plan, setup.where)
    planes, support = support_planes(np.where(contact[:, :, None, None], corners, np.nan), contact, plan.margin)
    out = Q.copy()
    yaw = feet_heading(corners, fps)  # upright: a turn about z alone (wxyz)
    out[:, 3:7] = np.stack([np.cos(yaw / 2), np.zeros_like(yaw), np.zeros_like(yaw), np.sin(yaw / 2)], axis=1)
    out[:, 2] = low_pass(Q[:, 2:3], fps, ROOT_CUTOFF_HZ)[:, 0]
    upper = np.flatnonzero(~foot_ancestor_mask(robot).any(axis=1))
    if len(upper):
        # the solve's per-frame noise filtered as the whole-body pipeline's last stage does
        # (the same cutoff in Hz at any rate), then rounded off to what the servos can follow;
        # without smoothing (RetargetOptions.smoothing off), only the exact velocity clamp
        lo, hi, vmax = robot.lower[upper], robot.upper[upper], robot.velocity_limit[upper]
        if setup.opt.smoothing:
            out[:, 7 + upper] = smooth_hinges(low_pass(Q[:, 7 + upper], fps, lower=lo, upper=hi),
                                              setup.servo[0][upper], setup.servo[1][upper], fps, vmax, lo, hi)
        else:
            out[:, 7 + upper] = np.clip(clamp_velocity(Q[:, 7 + upper], vmax, fps), lo, hi)
    # the CoM plan: near the feet's midpoint, its cart-table ZMP inside every frame's support polygon
    com_free = setup.points(Q)[2]
    com_ref = low_pass(corners[..., :2].mean(axis=(1, 2)), fps, COM_CUTOFF_HZ)   # between the feet
    com_z = low_pass(com_free[:, 2:3] - Q[:, 2:3] + out[:, 2:3], fps, ROOT_CUTOFF_HZ)[:, 0]
    acc = np.gradient(np.gradient(com_ref, axis=0), axis=0) * fps ** 2
    zmp0 = com_ref - (com_z / GRAVITY)[:, None] * acc   # the reference path's own cart-table ZMP
    shift, slack = cart_table_shift(zmp0, com_z, planes, support, fps, JERK_TIME)
    target = com_ref + shift
    # the root starts where the CoM plan puts it (the free solve's own root follows the human's
    # stride, not the shortened one), and its height comes down to what the legs reach from there
    out[:, :2] = target + np.median(Q[:, :2] - com_free[:, :2], axis=0)
    out[:, 2] = root_height(tracker, out, corners, fps)
    plan_q = out.copy()
    figures = {"rounds": 0, "cart_table_slack_m": float(slack.max(initial=0.0))}
    zmp = None  # the multi-body ZMP of ``out`` once measured
    for k in range(ZMP_ROUNDS):
        out, err = tracker.solve(plan_q, corners, target, fps, out if k else None)  # each round from the same plan
        zmp = None
        figures["rounds"] = k + 1
        figures["tracking_error_m"] = float(err.max())
        if k == ZMP_ROUNDS - 1 or err.max() > LOST:
            break
        zmp, com = multibody_zmp(out, fps, robot)
        d, _ = cart_table_shift(zmp, com[:, 2], planes, support, fps, JERK_TIME)
        if np.abs(d).max() < MIN_SHIFT:
            break
        target = target + d
    if zmp is None:  # the last round's ZMP was not measured
        zmp, _ = multibody_zmp(out, fps, robot)
    ok = support & np.isfinite(zmp).all(axis=1)
    outside = np.maximum(0.0, -support_margin(np.nan_to_num(zmp[ok]), planes[ok]))
    figures["zmp_outside_shrunk_soles_m"] = float(outside.max(initial=0.0))
    # the plan it stands on; no static CoM rule (a walking pattern balances by its ZMP, above)
    walked = replace(plan, labels=contact, pinned=np.ones_like(contact), targets=corners,
                     soles=np.where(contact[:, :, None, None], corners, np.nan), planes=planes,
                     support=np.zeros_like(support))
    return out, walked, figures

"""``project(human) -> human'``: the maths on synthetic poses, the properties on a real clip."""

from __future__ import annotations

import html

import numpy as np
import pytest

from motion2robot.errors import UserError
from motion2robot.motion.canonical import to_canonical
from motion2robot.motion.human import KP, SMPL22, SMPL22_PARENTS
from motion2robot.projection import (
    MotionArrayError,
    fill_torso,
    from_canonical,
    hinge_rms,
    human_torso,
    project,
    robot_frames,
    robot_points,
    unscale,
)
from motion2robot.retarget.scale import Scale, scaled_keypoints
from tests._projected import CLIP, clip_projection, direct_gap, op3
from tests._shared import MOTIONS, requires_shared
from tests._tensor import FakeTensor


def _pose(T: int = 5, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    base = np.zeros((len(SMPL22), 3))
    for name, p in {"pelvis": (0, 0, 0.9), "left_hip": (0, 0.1, 0.85), "right_hip": (0, -0.1, 0.85),
                    "spine1": (0, 0, 1.0), "spine2": (0, 0, 1.12), "spine3": (0, 0, 1.2), "neck": (0, 0, 1.4),
                    "left_collar": (0, 0.07, 1.33), "right_collar": (0, -0.07, 1.33), "head": (0.03, 0, 1.55),
                    "left_shoulder": (0, 0.18, 1.35), "right_shoulder": (0, -0.18, 1.35),
                    "left_elbow": (0, 0.2, 1.1), "right_elbow": (0, -0.2, 1.1), "left_wrist": (0.05, 0.2, 0.85),
                    "right_wrist": (0.05, -0.2, 0.85), "left_knee": (0.02, 0.1, 0.48), "right_knee": (0.02, -0.1, 0.48),
                    "left_ankle": (0, 0.1, 0.08), "right_ankle": (0, -0.1, 0.08), "left_foot": (0.12, 0.1, 0.02),
                    "right_foot": (0.12, -0.1, 0.02)}.items():
        base[KP[name]] = p
    return base + 0.02 * rng.standard_normal((T, len(SMPL22), 3))


def test_unscale_gives_back_the_robot_keypoints_whatever_the_fill() -> None:
    human = _pose()
    scale = Scale(0.3, 0.45, 0.25)
    mapped = np.array([n not in ("spine1", "spine2", "spine3", "left_collar", "right_collar") for n in SMPL22])
    robot_like = scaled_keypoints(_pose(seed=1), Scale(0.31, 0.4, 0.27))  # not a scaled copy of human
    for fill in (human, _pose(seed=2)):
        back = unscale(robot_like, mapped, scale, fill)
        assert np.allclose(scaled_keypoints(back, scale)[:, mapped], robot_like[:, mapped], atol=1e-12)
        assert np.allclose(back[:, ~mapped], fill[:, ~mapped])
    # the exact inverse when every joint is mapped
    assert np.allclose(unscale(scaled_keypoints(human, scale), np.ones(22, bool), scale, human * 0), human)


def test_fill_torso_points_the_spine_along_the_robot_torso_and_keeps_offsets() -> None:
    original = _pose()
    T = len(original)
    mapped = np.array([n not in ("spine1", "spine2", "spine3", "left_collar", "right_collar") for n in SMPL22])
    tilt = np.array([0.3, 0.0, 1.0]) / np.linalg.norm([0.3, 0.0, 1.0])
    robot_up = np.tile(tilt, (T, 1))
    filled = fill_torso(original, original + [0.5, 0.2, 0.0], robot_up, mapped)
    spine = filled[:, KP["neck"]] - filled[:, KP["spine1"]]
    assert np.allclose(spine / np.linalg.norm(spine, axis=1, keepdims=True), tilt, atol=1e-9)
    for name in ("spine1", "spine2", "left_collar"):  # rigid in the torso frame: distances to the neck kept
        d0 = np.linalg.norm(original[:, KP[name]] - original[:, KP["neck"]], axis=1)
        d1 = np.linalg.norm(filled[:, KP[name]] - filled[:, KP["neck"]], axis=1)
        assert np.allclose(d0, d1)
    assert np.allclose(filled[:, mapped], original[:, mapped] + [0.5, 0.2, 0.0])  # mapped rows untouched
    R = human_torso(original)
    assert np.allclose(np.einsum("tij,tik->tjk", R, R), np.eye(3), atol=1e-9)


def test_robot_frames_undo_the_tempo_and_the_rate() -> None:
    assert np.allclose(robot_frames(5, 20.0, 20.0, 2.0, 9), [0, 2, 4, 6, 8])
    assert np.allclose(robot_frames(3, 20.0, 100.0, 1.0, 11), [0, 5, 10])
    assert robot_frames(4, 20.0, 20.0, 3.0, 8)[-1] == 7  # clamped to the last robot frame


def test_keep_bones_sets_the_lengths_and_keeps_the_directions() -> None:
    from motion2robot.projection.maths import bone_drift, bone_lengths, keep_bones

    rng = np.random.default_rng(3)
    ref = _pose(4) + rng.normal(0, 0.01, (4, 22, 3))
    moved = ref + rng.normal(0, 0.05, ref.shape)
    kept = keep_bones(moved, ref)
    assert np.allclose(bone_lengths(kept), bone_lengths(ref)) and bone_drift(kept, ref) < 1e-12
    assert np.allclose(kept[:, 0], moved[:, 0])  # the pelvis where the round put it
    for j in range(1, 22):  # every bone along the direction the round gave it
        p = SMPL22_PARENTS[j]
        a, b = kept[:, j] - kept[:, p], moved[:, j] - moved[:, p]
        assert np.allclose(np.cross(a, b), 0.0, atol=1e-12) and (np.sum(a * b, axis=-1) > 0).all()
    loose = keep_bones(moved, ref, slack=0.05)
    assert 0.0 < bone_drift(loose, ref) <= 0.05 + 1e-12
    assert bone_drift(keep_bones(ref * 1.02, ref, slack=0.05), ref * 1.02) == pytest.approx(0.0)
    folded = moved.copy()
    folded[:, KP["left_knee"]] = folded[:, KP["left_hip"]]  # a thigh shrunk to a point
    back = keep_bones(folded, ref)
    assert np.allclose(back[:, KP["left_knee"]] - back[:, KP["left_hip"]],
                       ref[:, KP["left_knee"]] - ref[:, KP["left_hip"]])  # the reference's thigh


def test_from_canonical_inverts_the_readers_transform() -> None:
    theta = 0.7
    rz = np.array([[np.cos(theta), -np.sin(theta), 0], [np.sin(theta), np.cos(theta), 0], [0, 0, 1]])
    yup = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], dtype=float)
    tr = {"matrix": (rz @ yup * 0.01).tolist(), "offset": [0.1, -0.2, 0.3]}
    pts = _pose() * 100
    assert np.allclose(from_canonical(tr, to_canonical(tr, pts)), pts)
    assert np.allclose(from_canonical(None, pts), pts)


def test_bad_input_is_a_clear_exception() -> None:
    good = _pose(10)
    with pytest.raises(MotionArrayError, match=r"shape \(10, 21, 3\).*\(T, 22, 3\)"):
        project(good[:, :21])
    with pytest.raises(MotionArrayError, match="one sample at a time"):
        project(np.stack([good, good]))
    bad = good.copy()
    bad[4, 3, 1] = np.nan
    with pytest.raises(MotionArrayError, match="NaN/inf values in 1 frame.*frame 4"):
        project(bad)
    with pytest.raises(MotionArrayError, match="unknown layout"):
        project(good, layout="smpl")
    with pytest.raises(MotionArrayError, match="not numbers"):
        project(np.full((10, 22, 3), "a"))
    err = MotionArrayError("x")
    assert isinstance(err, ValueError) and isinstance(err, UserError)


@requires_shared
def test_projection_of_a_real_clip_keeps_its_frame_shape_and_executability() -> None:
    raw, p = clip_projection()
    assert p.positions.shape == raw.shape and p.human.num_frames == len(raw) and p.human.fps == 20.0
    # positions are in the input's own (y-up HumanML3D) frame: the distance there is the same figure
    assert np.allclose(np.linalg.norm(p.positions - raw, axis=-1), p.distance, atol=1e-6)
    assert p.distance.shape == (len(raw), 22) and set(p.joint_distance) == set(SMPL22)
    jd = p.joint_distance
    # the robot's head cannot follow the person's (op3 head tilt +-0.7 rad), its legs stand as the person's
    assert 0.0 < jd["left_ankle"] < jd["head"] and 0.0 < p.mean_distance < 0.3
    assert p.executable is True and p.human.contacts is not None
    assert "executable" in p.summary() and "cm" in p.summary()


@requires_shared
def test_idempotence_on_a_real_clip() -> None:
    """At x1.0 the robot's keypoints mapped back are robot-shaped: the retargeting reaches their
    poses exactly, so ``human'`` is the direct mapping and no correction runs (measured 2e-9 rad;
    the corrected human' of the previous releases came within 0.0002, with the solve alone the
    direct mapping comes back 0.07 rad away)."""
    from motion2robot.retarget import RetargetOptions, retarget_and_check

    _, p = clip_projection()
    again, report = retarget_and_check(p.human, op3())
    assert report is not None and report.feasible  # executable whenever human was
    rms = hinge_rms(p.robot_motion, again)
    assert p.reached and p.solver_rounds == () and np.array_equal(p.human.positions, p.direct.positions)
    assert rms < 1e-6 and again.meta["reached"] is True
    assert p.idempotence_rms == pytest.approx(rms, abs=1e-9)  # the figure it reports is the human' it returns
    assert direct_gap(p, RetargetOptions(reach=False)) > 0.03  # what the solve alone makes of it


@requires_shared
def test_viewer_draws_the_robots_version_on_the_human_and_the_report_lists_distances() -> None:
    from motion2robot.viz.html_report import projection_section, render_html
    from motion2robot.viz.scene import SceneOptions, human_tracks, make_playable

    _, p = clip_projection()
    robot = op3()
    human, projected = human_tracks(p.robot_motion, robot, p.original, SceneOptions(projected=True))
    assert projected.shape == human.shape == (p.robot_motion.num_frames, 22, 3)
    pts, mapped, _ = robot_points(p.robot_motion, robot)
    # the blue skeleton is the robot's keypoints, moved as a whole to where the human skeleton is drawn
    gap = projected[:, mapped] - pts[:, mapped]
    assert np.abs(gap - gap[0, 0]).max() < 1e-6 and abs(gap[0, 0, 2]) < 1e-9
    assert np.abs(human - projected).max() > 0.01  # the two differ where the robot could not follow
    assert human_tracks(p.robot_motion, robot, p.original, SceneOptions())[1] is None  # off by default
    play = make_playable(p.robot_motion, robot, human=p.original, options=SceneOptions(projected=True))
    assert play.projected is not None and "blue: the robot's version" in play.title
    title, body = projection_section(p.robot_motion, robot, p.original)
    assert body.count("<tr>") == 23 and "head" in body
    page = render_html(p.report, p.robot_motion, robot, human=p.original, keyframes=False)
    assert html.escape(title) in page


@requires_shared
def test_feature_input_comes_back_as_humanml3d_joints() -> None:
    from motion2robot.projection import as_human

    feats = np.load(MOTIONS / "humanml3d_vecs" / "M010968.npy")
    human = as_human(FakeTensor(feats), layout="humanml3d_vecs")
    joints = np.load(MOTIONS / CLIP)  # the same clip as joints: what p.positions holds for feature input
    assert np.abs(from_canonical(human.meta["canonical_transform"], human.positions) - joints).max() < 1e-4
    with pytest.raises(MotionArrayError, match="one sample at a time"):
        as_human(feats[None].repeat(2, 0), layout="humanml3d_vecs")


@requires_shared
def test_a_slowed_walk_comes_back_at_its_tempo_exactly() -> None:
    """The CMU walk walks at x1.25 (with the replay off: replayed, its steps pass at x1.0): human'
    is the robot's poses at the human's frames, contacts where the walking schedule planted the
    soles; its default retargeting plays those poses at x1.25 (the exact poses fail at x1.0), the
    frames between interpolated in joint space: the robot motion again, within 1e-4 rad."""
    from motion2robot.motion import read_motion
    from motion2robot.projection.maths import robot_frames
    from motion2robot.retarget import RetargetOptions, retarget_and_check

    robot = op3()
    human = read_motion(MOTIONS / "bvh" / "cmu_cc_002_01_walk.bvh")[0]
    opts = RetargetOptions(replay=False)
    p = project(human, robot, options=opts)
    assert p.robot_motion.meta["fallback"]["mode"] == "steps" and p.robot_motion.meta["tempo"] == 1.25
    assert p.reached and p.idempotence_rms < 1e-4
    u = robot_frames(human.num_frames, human.fps, p.robot_motion.fps, 1.25, p.robot_motion.num_frames)
    schedule = np.asarray(p.robot_motion.meta["schedule"], dtype=bool)
    np.testing.assert_array_equal(p.human.contacts, schedule[np.rint(u).astype(int)])
    again, report = retarget_and_check(p.human, robot, opts)
    assert again.meta["tempo"] == 1.25 and again.meta["retimed"] == {"from_tempo": 1.0} and report.feasible
    assert hinge_rms(p.robot_motion, again) < 1e-4

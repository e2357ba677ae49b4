"""Offscreen rendering (headless EGL), the scene's human skeleton and failing-frame marks, the
camera, video files and the ``sim`` command."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.motion.human import SMPL22, HumanMotion
from motion2robot.robot import load_robot
from motion2robot.robot.world import make_world
from motion2robot.robot_motion import RobotMotion
from motion2robot.viz.camera import camera_track, fit_distance
from motion2robot.viz.render import output_frames, parse_size, render_frames, write_video
from motion2robot.viz.scene import BONES, SceneOptions, add_skeleton, human_track, make_playable
from tests._shared import MOTIONS, requires_shared

SIZE = (160, 120)


@pytest.fixture(scope="module")
def robot():
    return load_robot("op3")


@pytest.fixture(scope="module")
def world(robot):
    return make_world(robot)


def wave_motion(robot, frames: int = 30, fps: float = 20.0, meta: dict | None = None) -> RobotMotion:
    """The nominal pose walking the root forward 5 cm/s while both arms swing (1.2 rad, 0.8 Hz)."""
    t = np.arange(frames) / fps
    q = np.tile(robot.nominal_qpos, (frames, 1))
    q[:, 0] += 0.05 * t
    for k, name in enumerate(robot.joint_names):
        if "sho_pitch" in name or name.endswith("_el"):
            q[:, 7 + k] = np.clip(q[:, 7 + k] + 1.2 * np.sin(2 * np.pi * 0.8 * t), robot.lower[k], robot.upper[k])
    return RobotMotion(q, fps, robot.joint_names, robot.name, meta or {})


def standing_human(frames: int = 30, fps: float = 20.0, height: float = 1.7) -> HumanMotion:
    """A crude T-less standing skeleton (z up, floor 0) swaying along x."""
    base = np.zeros((len(SMPL22), 3))
    z = {"pelvis": 0.95, "left_hip": 0.9, "right_hip": 0.9, "spine1": 1.05, "left_knee": 0.5, "right_knee": 0.5,
         "spine2": 1.2, "left_ankle": 0.08, "right_ankle": 0.08, "spine3": 1.3, "left_foot": 0.02,
         "right_foot": 0.02, "neck": 1.5, "left_collar": 1.45, "right_collar": 1.45, "head": height,
         "left_shoulder": 1.42, "right_shoulder": 1.42, "left_elbow": 1.15, "right_elbow": 1.15,
         "left_wrist": 0.9, "right_wrist": 0.9}
    for i, name in enumerate(SMPL22):
        base[i, 2] = z[name]
        base[i, 1] = 0.15 if name.startswith("left") else -0.15 if name.startswith("right") else 0.0
    pos = np.repeat(base[None], frames, axis=0)
    pos[:, :, 0] += 0.1 * np.sin(np.arange(frames) / fps * 2)[:, None]
    return HumanMotion(pos, fps)


class FakeReport:
    """The part of a FeasibilityReport the scene reads."""

    def __init__(self, failing: list[int]):
        self.checks = {"joint_limits": {"ok": True, "frames": []},
                       "balance": {"ok": False, "frames": failing}}


def test_headless_frames_are_not_blank_and_differ(robot, world):
    play = make_playable(wave_motion(robot), robot, options=SceneOptions(human="off"))
    frames = list(render_frames(world, play, [0, 8, 16], size=SIZE))
    assert len(frames) == 3
    for img in frames:
        assert img.shape == (SIZE[1], SIZE[0], 3) and img.dtype == np.uint8
        assert img.std() > 15  # not a blank/uniform image
    for a, b in [(0, 1), (1, 2), (0, 2)]:
        diff = np.abs(frames[a].astype(int) - frames[b].astype(int))
        assert diff.mean() > 0.5 and (diff.max(axis=2) > 30).sum() > 50


def test_human_skeleton_is_drawn_beside_the_robot(robot, world):
    motion = wave_motion(robot)
    human = standing_human()
    with_h = make_playable(motion, robot, human=human)
    without = make_playable(motion, robot, human=human, options=SceneOptions(human="off"))
    assert without.human is None and with_h.human.shape == (30, 22, 3)
    a, b = (next(render_frames(world, p, [5], size=SIZE, labels=False)) for p in (with_h, without))
    orange = (a[..., 0].astype(int) - a[..., 2] > 80) & (a[..., 1] > 80)
    assert orange.sum() > 40 and (b[..., 0].astype(int) - b[..., 2] > 80).sum() < orange.sum() / 4
    # beside: shifted to the robot's left (+y) by the side offset, feet on the floor, robot-sized
    off = SceneOptions().offset_for(robot)
    pelvis = with_h.human[:, 0]
    assert np.allclose(pelvis[0, :2], motion.qpos[0, :2] + [0, off], atol=1e-9)
    assert with_h.human[..., 2].min() >= 0.0
    assert with_h.human[0, :, 2].max() == pytest.approx(with_h.height, rel=1e-6)


def test_human_track_uses_the_retargeter_scale_and_root_path(robot):
    human = standing_human(frames=20, fps=10.0)
    motion = wave_motion(robot, frames=40, fps=20.0)
    s = 0.3
    ref = s * human.positions[:, 0, :2] + [0.4, -0.2]
    ref = np.repeat(ref, 2, axis=0)  # same path at the robot's 20 fps (nearest frames)
    meta = {"scale": {"legs": s, "arms": s, "height": s, "source": {}}, "human_root_xy": ref}
    track = human_track(motion.with_(meta=meta), robot, human, SceneOptions(human="overlay"))
    assert track.shape == (40, 22, 3)
    assert track[0, SMPL22.index("head"), 2] == pytest.approx(s * 1.7)
    assert np.abs(track[:, 0, :2] - ref).max() < 0.02  # resampled 10 -> 20 fps, aligned on the path
    # per-group ratios as the retargeter applies them: longer arms, same legs
    meta["scale"] = {"legs": s, "arms": 2 * s, "height": s}
    arms = human_track(motion.with_(meta=meta), robot, human, SceneOptions(human="overlay"))
    e, w = SMPL22.index("left_elbow"), SMPL22.index("left_wrist")
    assert np.linalg.norm(arms[0, w] - arms[0, e]) == pytest.approx(2 * np.linalg.norm(track[0, w] - track[0, e]))
    assert np.allclose(arms[:, SMPL22.index("left_ankle")], track[:, SMPL22.index("left_ankle")])


def test_skeleton_geoms_and_full_scene(robot, world):
    import mujoco

    scene = mujoco.MjvScene(world, maxgeom=30)
    pts = standing_human().positions[0]
    assert add_skeleton(scene, pts) == 30  # stops when the scene is full
    scene = mujoco.MjvScene(world, maxgeom=200)
    assert add_skeleton(scene, pts) == len(BONES) + 22 == scene.ngeom


def test_failing_frames_turn_the_robot_red(robot, world):
    motion = wave_motion(robot)
    play = make_playable(motion, robot, report=FakeReport([3]), options=SceneOptions(human="off"))
    assert play.failing == {3: ["balance"]} and "FAIL: balance" in play.label(3) and "FAIL" not in play.label(4)
    red, plain = (next(render_frames(world, play, [f], size=SIZE, labels=False)) for f in (3, 4))
    redness = [float((im[..., 0].astype(int) - im[..., 1] > 60).sum()) for im in (red, plain)]
    assert redness[0] > 3 * redness[1] + 50


def test_camera_follow_tracks_and_fixed_frames_the_path():
    T = 40
    path = np.column_stack([np.linspace(0, 2, T), np.zeros(T), np.zeros(T)])
    follow = camera_track([path], 0.5, 20.0, "follow")
    fixed = camera_track([path], 0.5, 20.0, "fixed")
    assert follow.lookat[-1, 0] > follow.lookat[0, 0] + 1.5
    assert np.allclose(fixed.lookat, fixed.lookat[0]) and fixed.lookat[0, 0] == pytest.approx(1.0)
    assert fixed.distance[0] > follow.distance[0]
    assert np.allclose(follow.lookat[:, 2], 0.25)
    assert fit_distance(1, 1) < fit_distance(2, 1) and fit_distance(2, 0.1, aspect=1) > fit_distance(2, 0.1, aspect=2)
    with pytest.raises(ValueError):
        camera_track([path], 0.5, 20.0, "orbit")


def test_gif_and_mp4_files(robot, world, tmp_path):
    play = make_playable(wave_motion(robot, frames=12), robot, options=SceneOptions(human="off"))
    frames = list(render_frames(world, play, range(6), size=SIZE, camera="fixed"))
    from PIL import Image

    gif = write_video(frames, tmp_path / "clip.gif", 20.0)
    with Image.open(gif) as im:
        assert im.n_frames == 6 and im.size == SIZE
    pytest.importorskip("imageio_ffmpeg")
    import imageio.v2 as imageio

    mp4 = write_video(frames, tmp_path / "clip.mp4", 20.0)
    with imageio.get_reader(str(mp4)) as r:
        got = [f for f in r]
    assert len(got) == 6 and got[0].shape == (SIZE[1], SIZE[0], 3)
    assert np.abs(got[3].astype(int) - frames[3]).mean() < 8  # lossy but the same picture


def test_output_frames_and_size_parsing():
    assert output_frames(5, 20.0, None).tolist() == [0, 1, 2, 3, 4]
    assert output_frames(41, 60.0, 30.0).tolist() == list(range(0, 41, 2))
    assert parse_size("641x480") == (640, 480)
    from motion2robot.errors import UserError

    for bad in ("640", "axb", "8x8"):
        with pytest.raises(UserError):
            parse_size(bad)


def test_physics_rollout_poses(robot):
    from motion2robot.viz.physics import rollout_qpos

    motion = wave_motion(robot, frames=20)
    q = rollout_qpos(motion, robot)
    assert q.shape == motion.qpos.shape and np.isfinite(q).all()
    assert q[:, 2].min() > 0.5 * motion.qpos[0, 2]  # still standing (root height)
    assert np.abs(q[:, 7:] - motion.joints).mean() < 0.15  # the servos track the arms
    assert not np.allclose(q, motion.qpos)  # it is a simulation, not a copy


def test_sim_command_renders_a_gif(robot, tmp_path, capsys):
    from motion2robot.cli import main

    src = wave_motion(robot, frames=10).save(tmp_path / "m.npz")
    out = tmp_path / "out.gif"
    assert main(["sim", str(src), "--render", str(out), "--size", "160x120", "--no-check"]) == 0
    assert "10 frames" in capsys.readouterr().out
    from PIL import Image

    with Image.open(out) as im:
        assert im.n_frames == 10
    assert main(["sim", str(src), "--render", str(tmp_path / "out.avi")]) == 2
    assert "mp4 or .gif" in capsys.readouterr().err


def test_viewer_without_a_display_says_to_render(robot, tmp_path, monkeypatch, capsys):
    from motion2robot.cli import main

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    src = wave_motion(robot, frames=5).save(tmp_path / "m.npz")
    assert main(["sim", str(src), "--no-check"]) == 2
    assert "--render" in capsys.readouterr().err


@requires_shared
def test_real_clip_skeleton_from_the_motion_source(robot, world):
    clip = MOTIONS / "humanml3d_joints" / "007005.npy"
    motion = wave_motion(robot, frames=20, meta={"source": str(clip)})
    play = make_playable(motion, robot)  # re-reads the source clip for the skeleton
    assert play.human is not None and play.human.shape == (20, 22, 3)
    assert play.human[0, :, 2].max() == pytest.approx(play.height, rel=1e-6)
    img = next(render_frames(world, play, [10], size=SIZE))
    assert img.std() > 15


@requires_shared
def test_sim_command_retargets_a_human_clip_and_plays_the_physics(tmp_path, capsys):
    from PIL import Image

    from motion2robot.cli import main

    out = tmp_path / "walk.gif"
    clip = MOTIONS / "humanml3d_joints" / "007005.npy"
    assert main(["sim", str(clip), "--physics", "--camera", "fixed", "--render", str(out),
                 "--size", "160x120", "--video-fps", "4"]) == 0
    text = capsys.readouterr().out
    assert "wrote" in text and "160x120" in text
    with Image.open(out) as im:
        assert im.n_frames == 40  # 199 frames at 20 fps -> 9.9 s at 4 fps
        im.seek(20)
        assert np.asarray(im.convert("RGB")).std() > 15

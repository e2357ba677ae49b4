"""What is drawn: the robot's world, the (scaled) human skeleton beside it, failing frames in red,
and optionally the robot's version of the human (:func:`motion2robot.projection.project_motion`,
the robot's keypoints mapped back onto the human skeleton) drawn in blue over the human skeleton.

The human skeleton is not part of the MuJoCo model: it is added to an ``MjvScene`` each frame as
user geoms (capsules between SMPL22 parent/child keypoints). Positions are metres in the robot's
world frame (z up, floor z = 0).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import mujoco
import numpy as np

from motion2robot.errors import UserError
from motion2robot.motion.human import SMPL22, SMPL22_PARENTS, HumanMotion
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion

log = logging.getLogger(__name__)

#: (parent, child) keypoint index pairs of the SMPL22 skeleton.
BONES: tuple[tuple[int, int], ...] = tuple((p, c) for c, p in enumerate(SMPL22_PARENTS) if p >= 0)
HUMAN_RGBA = np.array([0.95, 0.65, 0.2, 0.9], dtype=np.float32)
FAIL_RGBA = np.array([0.9, 0.1, 0.1, 1.0], dtype=np.float32)
PROJECTED_RGBA = np.array([0.15, 0.45, 0.95, 0.9], dtype=np.float32)
PLACEMENTS = ("beside", "overlay", "off")


@dataclass(frozen=True)
class SceneOptions:
    """human: ``beside`` (shifted sideways by ``side_offset`` metres, default from the robot's
    height), ``overlay`` (on the robot) or ``off``; ``tint``: how strongly failing frames turn the
    robot red (0..1); ``projected``: also draw the robot's version in the human's space (blue),
    placed with the human skeleton so the two compare joint by joint."""

    human: str = "beside"
    side_offset: float | None = None
    tint: float = 0.6
    projected: bool = False

    def offset_for(self, robot: Robot) -> float:
        if self.human != "beside":
            return 0.0
        return float(self.side_offset) if self.side_offset is not None else max(0.5, 0.6 * visual_height(robot))


def visual_height(robot: Robot) -> float:
    """Height (m) of the robot's geometry at the nominal pose: top of the highest geom's bounding
    sphere (robot.height is only the highest *keypoint*)."""
    data = robot.new_data()
    m = robot.model
    top = data.geom_xpos[:, 2] + m.geom_rbound if m.ngeom else np.array([robot.height])
    return float(max(robot.height, np.max(top)))


def human_scale(meta: Mapping[str, Any]) -> float | None:
    """The uniform human -> robot scale stored by the retargeter (``meta["scale"]``: a number or
    a dict with ``height`` / ``legs`` / ``arms``), or None."""
    s = meta.get("scale")
    if isinstance(s, (int, float)):
        return float(s)
    if isinstance(s, Mapping):
        for key in ("height", "uniform", "global", "legs"):
            if isinstance(s.get(key), (int, float)):
                return float(s[key])
        nums = [float(v) for v in s.values() if isinstance(v, (int, float))]
        return float(np.mean(nums)) if nums else None
    return None


def scaled_human(positions: np.ndarray, meta: Mapping[str, Any], robot: Robot) -> np.ndarray:
    """(T, 22, 3) human keypoints scaled as the retargeter did: per bone group (``legs``, ``arms``,
    ``height`` of ``meta["scale"]``, see :func:`motion2robot.retarget.scale.scaled_keypoints`),
    else uniformly by :func:`human_scale`, else by robot height / human height."""
    s = meta.get("scale")
    if isinstance(s, Mapping) and all(isinstance(s.get(k), (int, float)) for k in ("legs", "arms", "height")):
        from motion2robot.retarget.scale import Scale, scaled_keypoints

        return scaled_keypoints(positions, Scale(float(s["legs"]), float(s["arms"]), float(s["height"])))
    u = human_scale(meta)
    if u is None:
        h = float(np.max(positions[0, :, 2]))
        u = visual_height(robot) / h if h > 0 else 1.0
    return positions * u


def load_source_human(meta: Mapping[str, Any]) -> HumanMotion | None:
    """Re-read the human clip a robot motion was made from (``meta["source"]``/``["clip"]``), or
    None when it cannot be read (then the robot is shown alone)."""
    src = meta.get("source")
    if not src:
        return None
    try:
        from motion2robot.motion.read import read_motion

        clip, fmt = meta.get("clip"), meta.get("format")
        clips = read_motion(src, clip=int(clip) if clip is not None else None, format=fmt or None)
        return clips[0] if clips else None
    except Exception as err:  # a moved/deleted source must not stop the viewer
        log.warning("human skeleton not shown: cannot re-read %s (%s)", src, err)
        return None


def resample_positions(positions: np.ndarray, fps_in: float, n_out: int, fps_out: float) -> np.ndarray:
    """(n_out, J, 3) positions at ``fps_out`` by linear interpolation in time (clamped at the ends)."""
    t = np.arange(n_out) / fps_out * fps_in
    t = np.clip(t, 0, positions.shape[0] - 1)
    i0 = np.floor(t).astype(int)
    i1 = np.minimum(i0 + 1, positions.shape[0] - 1)
    w = (t - i0)[:, None, None]
    return positions[i0] * (1 - w) + positions[i1] * w


def _scaled_track(motion: RobotMotion, robot: Robot, human: HumanMotion) -> np.ndarray:
    """(T_robot, 22, 3) scaled keypoints of ``human`` at each robot frame: human time runs
    ``meta["tempo"]`` times slower on the robot (the tempo stretch)."""
    tempo = float(motion.meta.get("tempo") or 1.0)
    return resample_positions(scaled_human(human.positions, motion.meta, robot), human.fps / tempo,
                              motion.num_frames, motion.fps)


def _placement(pos: np.ndarray, motion: RobotMotion, robot: Robot, options: SceneOptions) -> np.ndarray:
    """(2,) xy shift of a scaled track: its pelvis ground path aligned with ``meta["human_root_xy"]``
    when the retargeter stored it, else its frame-0 position with the robot root's; plus the
    sideways offset of ``beside``."""
    pelvis = pos[:, SMPL22.index("pelvis"), :2]
    ref = motion.meta.get("human_root_xy")
    ref = np.asarray(ref, dtype=float) if ref is not None else None
    if ref is not None and ref.shape == (motion.num_frames, 2):
        shift = np.mean(ref - pelvis, axis=0)
    else:
        shift = motion.qpos[0, :2] - pelvis[0]
    return shift + [0.0, options.offset_for(robot)]


def human_track(motion: RobotMotion, robot: Robot, human: HumanMotion | None = None,
                options: SceneOptions = SceneOptions()) -> np.ndarray | None:
    """(T, 22, 3) scaled human keypoints for each robot frame, in the robot's world frame, shifted
    sideways (+y, the robot's left) for ``beside``; None when ``off`` or unknown.

    Scale: see :func:`scaled_human`; time: the robot's tempo factor undone.
    Placement: the scaled pelvis ground path is aligned with ``meta["human_root_xy"]`` when the
    retargeter stored it, else its frame-0 position with the robot root's."""
    tracks = human_tracks(motion, robot, human, options)
    return tracks[0] if tracks else None


def human_tracks(motion: RobotMotion, robot: Robot, human: HumanMotion | None = None,
                 options: SceneOptions = SceneOptions()) -> tuple[np.ndarray, np.ndarray | None] | None:
    """(human track, projected track or None) placed as :func:`human_track` says; the projected
    one (``options.projected``) is ``human'`` of :func:`motion2robot.projection.project_motion`,
    scaled and placed exactly as the human (it lies on the human where the robot did what the
    person did). None when the human is ``off`` or unknown."""
    if options.human == "off":
        return None
    human = human if human is not None else load_source_human(motion.meta)
    if human is None:
        return None
    pos = _scaled_track(motion, robot, human)
    shift = _placement(pos, motion, robot, options)
    pos[:, :, :2] += shift
    projected = None
    if options.projected:
        from motion2robot.projection import project_motion

        try:
            projected = _scaled_track(motion, robot, project_motion(motion, robot, human))
            projected[:, :, :2] += shift
        except UserError as err:  # e.g. a motion made without the retargeter's meta (no scale)
            log.warning("the robot's version in the human's space is not shown: %s", err)
    return pos, projected


def add_skeleton(scene: mujoco.MjvScene, points: np.ndarray, rgba: np.ndarray = HUMAN_RGBA,
                 radius: float = 0.015) -> int:
    """Append capsules (bones) and spheres (joints) for (22, 3) ``points`` to ``scene``; returns
    how many geoms were added (stops silently when the scene is full)."""
    added = 0
    eye = np.eye(3).ravel()
    for p, c in BONES:
        if scene.ngeom >= scene.maxgeom:
            return added
        g = scene.geoms[scene.ngeom]
        mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_CAPSULE, np.zeros(3), np.zeros(3), eye, rgba)
        mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_CAPSULE, radius, points[p], points[c])
        scene.ngeom += 1
        added += 1
    for q in points:
        if scene.ngeom >= scene.maxgeom:
            return added
        mujoco.mjv_initGeom(scene.geoms[scene.ngeom], mujoco.mjtGeom.mjGEOM_SPHERE,
                            np.array([1.4 * radius, 0, 0]), q, eye, rgba)
        scene.ngeom += 1
        added += 1
    return added


def add_marker(scene: mujoco.MjvScene, pos: np.ndarray, radius: float, rgba: np.ndarray = FAIL_RGBA) -> None:
    """A flat translucent disc of ``radius`` (m) centred at ``pos``: the failing-frame mark on the
    floor under the robot."""
    if scene.ngeom < scene.maxgeom:
        mujoco.mjv_initGeom(scene.geoms[scene.ngeom], mujoco.mjtGeom.mjGEOM_CYLINDER,
                            np.array([radius, 0.001, 0.0]), pos, np.eye(3).ravel(),
                            np.array([rgba[0], rgba[1], rgba[2], 0.45], dtype=np.float32))
        scene.ngeom += 1


def tint_robot(scene: mujoco.MjvScene, model: mujoco.MjModel, amount: float,
               rgba: np.ndarray = FAIL_RGBA) -> None:
    """Blend the colour of the robot's geoms (those on a moving body) towards ``rgba``."""
    if amount <= 0:
        return
    for i in range(scene.ngeom):
        g = scene.geoms[i]
        if g.objtype == mujoco.mjtObj.mjOBJ_GEOM and g.objid >= 0 and model.geom_bodyid[g.objid] > 0:
            g.rgba[:3] = (1 - amount) * np.asarray(g.rgba[:3]) + amount * rgba[:3]


@dataclass(frozen=True, eq=False)
class Playable:
    """Everything shown for one clip, frame by frame.

    qpos: (T, nq) robot poses (kinematic replay or physics rollout); fps: frames per second;
    human: (T, 22, 3) skeleton keypoints or None; failing: {frame: [failed check names]};
    title: one line (robot, source); tint: failing-frame red blend (0..1); height: the robot's
    visual height (m), for camera framing; projected: (T, 22, 3) the robot's version in the
    human's space (drawn blue) or None."""

    qpos: np.ndarray
    fps: float
    human: np.ndarray | None = None
    failing: Mapping[int, list[str]] = field(default_factory=dict)
    title: str = ""
    tint: float = 0.6
    height: float = 1.0
    projected: np.ndarray | None = None

    @property
    def num_frames(self) -> int:
        return int(self.qpos.shape[0])

    def decorate(self, scene: mujoco.MjvScene, model: mujoco.MjModel, frame: int) -> None:
        """Add this frame's extras to a scene already filled by ``mjv_updateScene``."""
        if frame in self.failing:
            tint_robot(scene, model, self.tint)
            add_marker(scene, np.array([*self.qpos[frame, :2], 0.002]), 0.35 * self.height)
        radius = max(0.005, 0.025 * self.height)
        if self.human is not None:
            add_skeleton(scene, self.human[min(frame, len(self.human) - 1)], radius=radius)
        if self.projected is not None:
            add_skeleton(scene, self.projected[min(frame, len(self.projected) - 1)], PROJECTED_RGBA, 0.8 * radius)

    def label(self, frame: int) -> str:
        """Overlay text: frame, time and the checks failing there."""
        text = f"{frame}/{self.num_frames - 1}  {frame / self.fps:.2f} s"
        if frame in self.failing:
            text += "  FAIL: " + ", ".join(self.failing[frame])
        return text


def make_playable(motion: RobotMotion, robot: Robot, *, human: HumanMotion | None = None,
                  report: Any = None, options: SceneOptions = SceneOptions(),
                  qpos: np.ndarray | None = None) -> Playable:
    """The robot motion (or ``qpos`` of the same length, e.g. a physics rollout) with the scaled
    human beside it and the failing frames of ``report`` (a FeasibilityReport) marked."""
    src = motion.meta.get("source")
    title = f"{motion.robot}" + (f"  <- {Path(str(src)).name}" if src else "")
    tempo, fallback = motion.meta.get("tempo"), motion.meta.get("fallback")
    if tempo is not None and float(tempo) != 1.0:
        title += f"  tempo x{float(tempo):.2f}"
    if fallback:
        title += f"  legs: {fallback.get('mode')}"
    tracks = human_tracks(motion, robot, human, options)
    if tracks is not None and tracks[1] is not None:
        title += "  blue: the robot's version"
    return Playable(
        qpos=np.asarray(motion.qpos if qpos is None else qpos, dtype=float),
        fps=motion.fps,
        human=tracks[0] if tracks else None,
        projected=tracks[1] if tracks else None,
        failing=failing_frames(report),
        title=title,
        tint=options.tint,
        height=visual_height(robot),
    )


def failing_frames(report: Any) -> dict[int, list[str]]:
    """{frame: [names of the verdict checks failing there]} from a FeasibilityReport (or None);
    skipped checks and the informative ``trajectory`` figure are left out."""
    from motion2robot.validate.report import VERDICT_CHECKS

    out: dict[int, list[str]] = {}
    if report is None:
        return out
    for name, res in report.checks.items():
        if name not in VERDICT_CHECKS or res.get("ok", True) or res.get("skipped"):
            continue
        for f in res.get("frames", []) or []:
            out.setdefault(int(f), []).append(name)
    return out

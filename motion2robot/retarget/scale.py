"""Human-to-robot scale, calibrated from the clip's own bone lengths and the robot's nominal posture.

Three ratios (robot length / human length): ``legs`` (hip->knee->ankle; it also scales the root
path, so it sets the root height and the step length), ``arms`` (shoulder->elbow->wrist) and
``height`` (pelvis->neck; spine, neck, head and collar bones). A ratio the robot's keypoints
cannot measure falls back to ``legs``; the robot TOML's ``[scale]`` overrides any of them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2robot.motion.human import KP, SMPL22, SMPL22_PARENTS, HumanMotion
from motion2robot.robot.robot import Robot

_CHAINS = {
    "legs": (("left_hip", "left_knee", "left_ankle"), ("right_hip", "right_knee", "right_ankle")),
    "arms": (("left_shoulder", "left_elbow", "left_wrist"), ("right_shoulder", "right_elbow", "right_wrist")),
    "height": (("pelvis", "neck"),),
}
#: Which ratio scales the bone from each SMPL22 joint's parent to the joint.
BONE_GROUP: dict[str, str] = {
    **{k: "legs" for k in ("left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle",
                           "left_foot", "right_foot")},
    **{k: "arms" for k in ("left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist")},
    **{k: "height" for k in ("spine1", "spine2", "spine3", "neck", "left_collar", "right_collar", "head")},
}


@dataclass(frozen=True)
class Scale:
    """Robot/human length ratios (dimensionless) and where each came from ("auto"/"config"/"fallback")."""

    legs: float
    arms: float
    height: float
    source: tuple[tuple[str, str], ...] = ()

    def as_dict(self) -> dict:
        return {"legs": self.legs, "arms": self.arms, "height": self.height, "source": dict(self.source)}


def _chain_length(points: dict[str, np.ndarray], chain: tuple[str, ...]) -> float:
    return float(sum(np.linalg.norm(points[b] - points[a], axis=-1) for a, b in zip(chain, chain[1:])))


def human_length(human: HumanMotion, group: str) -> float:
    """Median over frames of the group's chain length, averaged over sides (m)."""
    pts = {k: human.positions[:, KP[k]] for k in SMPL22}
    lens = [np.median(sum(np.linalg.norm(pts[b] - pts[a], axis=-1) for a, b in zip(c, c[1:]))) for c in _CHAINS[group]]
    return float(np.mean(lens))


def robot_length(robot: Robot, group: str) -> float | None:
    """The group's chain length at the robot's nominal posture (m), or None when not mapped."""
    xpos = robot.nominal_site_xpos
    pts = {k: xpos[s] for k, s in zip(robot.keypoints, robot.keypoint_sites)}
    chains = [c for c in _CHAINS[group] if all(k in pts for k in c)]
    if not chains:
        return None
    return float(np.mean([_chain_length(pts, c) for c in chains]))


def auto_scale(human: HumanMotion, robot: Robot) -> Scale:
    """The three ratios for this clip on this robot (config overrides win)."""
    values: dict[str, float] = {}
    source: dict[str, str] = {}
    for group in ("legs", "arms", "height"):
        if group in robot.config.scale:
            values[group], source[group] = float(robot.config.scale[group]), "config"
            continue
        r, h = robot_length(robot, group), human_length(human, group)
        if r is not None and h > 1e-6:
            values[group], source[group] = r / h, "auto"
    if "legs" not in values:  # legs unmapped: whole-body height ratio
        hh = float(np.median(human.positions[..., 2].max(axis=1)))
        values["legs"], source["legs"] = robot.height / max(hh, 1e-6), "fallback"
    for group in ("arms", "height"):
        if group not in values:
            values[group], source[group] = values["legs"], "fallback"
    return Scale(values["legs"], values["arms"], values["height"], tuple(source.items()))


def scaled_keypoints(positions: np.ndarray, scale: Scale) -> np.ndarray:
    """(T, 22, 3) human keypoints -> robot-sized targets: the pelvis path (xyz) is scaled by
    ``legs`` and every bone vector by its group's ratio, rebuilt from the pelvis outwards."""
    ratio = {"legs": scale.legs, "arms": scale.arms, "height": scale.height}
    out = np.empty_like(positions, dtype=np.float64)
    out[:, 0] = positions[:, 0] * scale.legs
    for j in range(1, len(SMPL22)):
        p = SMPL22_PARENTS[j]
        out[:, j] = out[:, p] + ratio[BONE_GROUP[SMPL22[j]]] * (positions[:, j] - positions[:, p])
    return out


"""BVH files -> canonical HumanMotion: parse, map the skeleton onto SMPL22, FK, canonicalise.

A reference pose in frame 0 (CMU's T-pose) is detected and dropped (meta "dropped"). Up axis and units are detected from the body (head above feet; the subject's size) unless
given; the floor is estimated from the feet, never assumed at y = 0.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np

from motion2robot.motion.bvh import forward_kinematics, parse_bvh
from motion2robot.motion.canonical import canonicalize
from motion2robot.motion.checks import fail
from motion2robot.motion.human import SMPL22, HumanMotion
from motion2robot.motion.options import ReadOptions
from motion2robot.motion.skeletons import choose_map, describe_map, load_name_map


def _user_map(opts: ReadOptions) -> Mapping[str, str] | None:
    if opts.name_map is None:
        return None
    if isinstance(opts.name_map, Mapping):
        return opts.name_map
    return load_name_map(opts.name_map)


def keypoint_positions(joints: dict[str, np.ndarray], mapping: dict[str, list[str]]) -> np.ndarray:
    """(T, 22, 3): each SMPL22 keypoint as the mean of its mapped joints."""
    return np.stack([np.mean([joints[n] for n in mapping[kp]], axis=0) for kp in SMPL22], axis=1)


def reference_first_frame(pos: np.ndarray) -> bool:
    """True when frame 0 is a reference pose (e.g. CMU's T-pose) rather than motion: the jump
    from frame 0 to 1 exceeds 20x the clip's median per-frame keypoint step and 10 % of the
    body's size."""
    if pos.shape[0] < 4:
        return False
    step = np.linalg.norm(np.diff(pos, axis=0), axis=-1).max(axis=1)
    size = np.ptp(pos[1:], axis=1).max(axis=1).mean()
    return bool(step[0] > 20.0 * np.median(step[1:]) and step[0] > 0.1 * size)


def _snap_fps(frame_time: float) -> float:
    fps = 1.0 / frame_time
    return float(round(fps)) if abs(fps - round(fps)) < 1e-3 * fps else fps


def read_bvh(path: Path, opts: ReadOptions) -> list[HumanMotion]:
    """One clip per BVH file (``clip`` may only be 0)."""
    if opts.clip not in (None, 0, -1):
        raise fail(path, f"holds one clip, --clip {opts.clip} is out of range", "pass --clip 0 or omit it")
    clip = parse_bvh(path, strict=bool(getattr(opts, "strict", False)))
    names = list(clip.skeleton.names)
    sk = clip.skeleton
    children = {p for p in sk.parents if p >= 0}
    ends = [not sk.channels[j] and j not in children and j > 0 for j in range(len(names))]
    preset, mapping = choose_map(path, names, _user_map(opts), (sk.parents, sk.offsets, ends))
    joints = forward_kinematics(clip, {n for parts in mapping.values() for n in parts})
    pos = keypoint_positions(joints, mapping)
    extra = {}
    if reference_first_frame(pos):
        pos = pos[1:]
        extra["dropped"] = "frame 0 (a reference pose, not motion)"
    fps = opts.fps or _snap_fps(clip.frame_time)
    return [canonicalize(
        path, pos, fps, up=opts.up, up_source="--up", units=opts.units, units_source="--units",
        source_fps=_snap_fps(clip.frame_time),
        meta={"source": str(path), "format": "bvh", "clip": 0, "skeleton": preset,
              "joint_map": describe_map(mapping),
              "bvh_joints": len([n for n in names if not n.endswith("_End")]),
              "frame_time": clip.frame_time, **extra})]

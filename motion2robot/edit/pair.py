"""``retarget_edit(source, edit, robot)``: both motions on the robot, the edit keeping the source's
robot trajectory for every hinge whose body parts it did not change.

The two human motions are compared on the frames both have, after resampling the edit to the
source's rate (editors may change either). The source is retargeted as usual (its tempo and legs
policies choose a slow-down and whole body or stance); the edit then with the source's scale, tempo
and legs fixed, so both robot motions have the same frames; the two are composed per hinge
(:mod:`~motion2robot.edit.compose`), the human frames' changes mapped onto the robot's frames.
Nothing is re-solved after the composition. With ``balance_override``, balance may override the kept joints where it must: in
the retargeted window, frames where the composed motion fails the (kinematic) balance check while
both the source's and the edit's own robot motions pass it take every hinge and the root from the
edit (with the same blend), and are reported. It is off by default: three more kinematic checks
of the window cost about as much as the edit's retargeting, and kept joints then stay exact.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from motion2robot.edit.compose import compose
from motion2robot.edit.parts import PARTS, TOLERANCE, hinge_parts, part_deviation
from motion2robot.errors import InputFileError
from motion2robot.motion.human import SMPL22_PARENTS, HumanMotion
from motion2robot.motion.ops import resample, trim
from motion2robot.robot_motion import RobotMotion
from motion2robot.util.ranges import frame_ranges

#: Seconds of blend between the source's and the edit's trajectory at each end of an edit.
BLEND_SECONDS = 0.25
#: Mean relative bone-length difference above which two motions are different bodies.
SKELETON_TOLERANCE = 0.15
#: A robot hinge differs from the source's where it moved by more than this (rad).
HINGE_EPS = 1e-6


@dataclass(frozen=True)
class EditResult:
    """source / edited: robot motions over the common frames. human: {part: {"frames", "max_m"}}
    for the parts the edit changed; robot: {hinge: {"frames", "max_rad"}} for the hinges that
    differ from the source's; info: tolerance, blend, retargeted window, timings."""

    source: RobotMotion
    edited: RobotMotion
    human: dict[str, dict[str, Any]]
    robot: dict[str, dict[str, Any]]
    info: dict[str, Any] = field(default_factory=dict)


def _bones(m: HumanMotion) -> np.ndarray:
    p = m.positions
    return np.array([np.median(np.linalg.norm(p[:, j] - p[:, q], axis=-1))
                     for j, q in enumerate(SMPL22_PARENTS) if q >= 0])


def common_frames(source: HumanMotion, edit: HumanMotion, name: str = "the pair") -> tuple[HumanMotion, HumanMotion]:
    """Both motions at the source's rate, trimmed to the frames both have; InputFileError when
    they share fewer than 2 frames or are different bodies."""
    if abs(edit.fps - source.fps) > 1e-9:
        edit = resample(edit, source.fps)
    t = min(source.num_frames, edit.num_frames)
    if t < 2:
        raise InputFileError(f"{name}: the two motions have no overlapping frames ({source.num_frames} and "
                             f"{edit.num_frames} at {source.fps:g} fps); give an edit of this source")
    a, b = _bones(source), _bones(edit)
    diff = float(np.mean(np.abs(a - b) / np.maximum(a, 1e-6)))
    if diff > SKELETON_TOLERANCE:
        raise InputFileError(f"{name}: the two motions have different skeletons (bone lengths differ by "
                             f"{diff:.0%} on average); give an edit made from this source motion")
    return trim(source, 0, t), trim(edit, 0, t)


def _fixed_like(opts, src: RobotMotion):
    """The options with the tempo and legs the source's policies chose (so frames line up)."""
    tempo = src.meta.get("tempo")
    legs = (src.meta.get("fallback") or {}).get("mode") if isinstance(src.meta.get("fallback"), dict) else None
    if legs not in ("whole", "stance"):
        legs = opts.legs if getattr(opts, "legs", "auto") in ("whole", "stance") else "whole"
    changes = {"legs": legs}
    if isinstance(tempo, (int, float)):
        changes["tempo"] = float(tempo)
    return replace(opts, **changes)


def _same_frames(q: np.ndarray, t: int) -> np.ndarray:
    """(T', nq) -> (t, nq) by linear interpolation (quaternions renormalised); q itself if T' == t."""
    if len(q) == t:
        return q
    u = np.linspace(0, len(q) - 1, t)
    out = np.stack([np.interp(u, np.arange(len(q)), q[:, k]) for k in range(q.shape[1])], axis=1)
    out[:, 3:7] /= np.linalg.norm(out[:, 3:7], axis=1, keepdims=True)
    return out


def _balance_must_override(robot, src: RobotMotion, q_comp: np.ndarray, q_edit: np.ndarray,
                           window: tuple[int, int]) -> list[int]:
    """Frames of the window where the composed motion fails the balance check and neither the
    source's nor the edit's own robot motion does (kinematic checks on the window's frames, so the
    three share the window's edge effects)."""
    from motion2robot.validate import CheckOptions, check

    if not src.meta.get("balance", True):
        return []
    lo, hi = window
    opts = CheckOptions(physics=False)

    def failing(q: np.ndarray) -> set[int]:
        m = RobotMotion(q[lo:hi], src.fps, src.joint_names, src.robot, {})
        return {lo + int(f) for f in check(m, robot, opts).checks.get("balance", {}).get("frames", [])}

    bad = failing(q_comp)
    if bad:
        bad -= failing(src.qpos)
    return sorted(bad - failing(q_edit)) if bad else []


def retarget_edit(source: HumanMotion, edit: HumanMotion, robot, options=None, *,
                  tolerance: float = TOLERANCE, blend_seconds: float = BLEND_SECONDS,
                  balance_override: bool = False, name: str = "the pair") -> EditResult:
    """Retarget a (source, edit) pair; see the module docstring."""
    from motion2robot.retarget import RetargetOptions, retarget
    from motion2robot.retarget.scale import auto_scale

    source, edit = common_frames(source, edit, name)
    t0 = time.perf_counter()
    dev = part_deviation(source, edit)
    changed = {p: d > tolerance for p, d in dev.items()}
    opts = options or RetargetOptions()
    if opts.scale is None:
        opts = replace(opts, scale=auto_scale(source, robot))
    src = retarget(source, robot, opts)
    t_src = time.perf_counter() - t0
    blend = int(round(blend_seconds * src.fps))
    t_r = src.num_frames
    to_human = np.rint(np.arange(t_r) * (source.num_frames - 1) / max(t_r - 1, 1)).astype(int)
    changed = {p: c[to_human] for p, c in changed.items()}  # on the robot's frames (tempo may stretch)
    q_edit = src.qpos.copy()
    window = None
    if np.any(list(changed.values())):
        window = (0, t_r)
        q_edit = _same_frames(retarget(edit, robot, _fixed_like(opts, src)).qpos, t_r)
    parts = hinge_parts(robot)
    qpos, weights = compose(src.qpos, q_edit, changed, parts, blend)
    overridden: list[int] = []
    if window is not None and balance_override:
        overridden = _balance_must_override(robot, src, qpos, q_edit, window)  # type: ignore[arg-type]
        if overridden:
            must = np.zeros(source.num_frames, bool)
            must[overridden] = True
            qpos, weights = compose(src.qpos, q_edit, {p: c | must for p, c in changed.items()}, parts, blend)
    elapsed = time.perf_counter() - t0
    human = {p: {"frames": frame_ranges(np.flatnonzero(c)), "max_m": float(dev[p][c].max()),
                 "frames_changed": int(c.sum())} for p, c in ((p, dev[p] > tolerance) for p in dev) if c.any()}
    robot_diff = {}
    for h, jn in enumerate(robot.joint_names):
        d = np.abs(qpos[:, 7 + h] - src.qpos[:, 7 + h])
        moved = np.flatnonzero(d > HINGE_EPS)
        if moved.size:
            robot_diff[jn] = {"frames": frame_ranges(moved), "max_rad": float(d.max()), "frames_changed": int(moved.size)}
    root = np.abs(qpos[:, :7] - src.qpos[:, :7]).max(axis=1)
    if (root > HINGE_EPS).any():
        robot_diff["root"] = {"frames": frame_ranges(np.flatnonzero(root > HINGE_EPS)),
                              "max_rad": float(root.max()), "frames_changed": int((root > HINGE_EPS).sum())}
    info = {"tolerance_m": tolerance, "blend_frames": blend, "retargeted_window": window,
            "tempo": src.meta.get("tempo", 1.0), "robot_frames": t_r,
            "balance_override_frames": frame_ranges(overridden) if overridden else None,
            "frames": source.num_frames, "fps": source.fps, "parts": list(PARTS),
            "seconds": {"source": round(t_src, 3), "total": round(elapsed, 3)}}
    edited = RobotMotion(qpos, src.fps, src.joint_names, src.robot,
                         {**dict(src.meta), **{k: v for k, v in edit.meta.items() if k in ("source", "prompt", "clip")},
                          "edit": {"human_parts_changed": sorted(human), "source_weight_min": float(weights.min()),
                                   **info}})
    return EditResult(src, edited, human, robot_diff, info)

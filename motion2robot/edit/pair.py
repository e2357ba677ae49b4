"""``retarget_edit(source, edit, robot)``: both motions on the robot, the edit keeping the source's
robot trajectory for every hinge whose body parts it did not change.

The two human motions are compared on the frames both have, after resampling the edit to the
source's rate (editors may change either). The source is retargeted as usual (its tempo and legs
policies choose a slow-down and whole body or stance); the edit then with the source's scale, tempo
and legs fixed, only over the frames it changed plus the blend and a margin
(:mod:`~motion2robot.edit.window`); the two are composed per hinge
(:mod:`~motion2robot.edit.compose`), the human frames' changes mapped onto the robot's frames by
time. Kept joints are first exactly the source's. Where that composition fails the balance or
torque check while the source's and the edit's own motions pass (:mod:`~motion2robot.edit.override`),
balance overrides the kept joints in those frames only (every hinge and the root take the edit's
own solution there, with the same blend), and the frames, joints and reasons are reported; with
``balance_override=False`` the kept joints stay exact and the need is reported instead (the edit
is then infeasible there).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from motion2robot.edit.compose import compose
from motion2robot.edit.override import OverrideNeed, must_override
from motion2robot.edit.parts import PARTS, TOLERANCE, hinge_parts, part_deviation
from motion2robot.edit.window import edit_solution, human_frames
from motion2robot.errors import InputFileError
from motion2robot.motion.human import SMPL22_PARENTS, HumanMotion
from motion2robot.motion.ops import resample, trim
from motion2robot.retarget.options import LEG_MODES
from motion2robot.robot_motion import RobotMotion
from motion2robot.util.ranges import frame_ranges

#: Seconds of blend between the source's and the edit's trajectory at each end of an edit.
BLEND_SECONDS = 0.25
#: Seconds of the edit's solution beyond the blend (its trimmed solve's edge effects fall there).
MARGIN_SECONDS = 0.3
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
    if legs not in LEG_MODES:
        legs = opts.legs if getattr(opts, "legs", "auto") in LEG_MODES else "whole"
    changes = {"legs": legs}
    if isinstance(tempo, (int, float)):
        changes["tempo"] = float(tempo)
    return replace(opts, **changes)


def _moved(q: np.ndarray, ref: np.ndarray, names) -> dict[str, dict[str, Any]]:
    """{hinge or "root": {"frames", "max_rad", "frames_changed"}} where ``q`` differs from ``ref``."""
    out = {}
    for h, jn in enumerate(names):
        d = np.abs(q[:, 7 + h] - ref[:, 7 + h])
        moved = np.flatnonzero(d > HINGE_EPS)
        if moved.size:
            out[jn] = {"frames": frame_ranges(moved), "max_rad": float(d.max()), "frames_changed": int(moved.size)}
    root = np.abs(q[:, :7] - ref[:, :7]).max(axis=1)
    if (root > HINGE_EPS).any():
        out["root"] = {"frames": frame_ranges(np.flatnonzero(root > HINGE_EPS)), "max_rad": float(root.max()),
                       "frames_changed": int((root > HINGE_EPS).sum())}
    return out


def _override_info(need: OverrideNeed | None, allowed: bool, q_final: np.ndarray, q_comp: np.ndarray,
                   names) -> dict[str, Any] | None:
    """The report of the balance override: None when nothing needed it."""
    if need is None or not (need.frames or need.unresolved):
        return None
    return {"allowed": allowed, "applied": bool(allowed and need.frames),
            "frames": frame_ranges(need.frames) if need.frames else None, "frame_list": list(need.frames),
            "why": list(need.why),
            "joints": {j: d["frames"] for j, d in _moved(q_final, q_comp, names).items()} if allowed else {},
            "unresolved_frames": frame_ranges(need.unresolved) if need.unresolved else None}


def retarget_edit(source: HumanMotion, edit: HumanMotion, robot, options=None, *,
                  tolerance: float = TOLERANCE, blend_seconds: float = BLEND_SECONDS,
                  balance_override: bool = True, name: str = "the pair") -> EditResult:
    """Retarget a (source, edit) pair; see the module docstring. ``balance_override=False``
    forbids the override (kept joints exact; the need is still reported)."""
    from motion2robot.retarget import RetargetOptions, retarget
    from motion2robot.retarget.scale import auto_scale

    source, edit = common_frames(source, edit, name)
    t0 = time.perf_counter()
    dev = part_deviation(source, edit)
    changed_h = {p: d > tolerance for p, d in dev.items()}
    opts = options or RetargetOptions()
    if opts.scale is None:
        opts = replace(opts, scale=auto_scale(source, robot))
    src = retarget(source, robot, opts)
    t_src = time.perf_counter() - t0
    blend = int(round(blend_seconds * src.fps))
    t_r = src.num_frames
    tempo = float(src.meta.get("tempo", 1.0) or 1.0)
    to_human = np.clip(np.rint(human_frames(np.arange(t_r), src.fps, tempo, source.fps)), 0,
                       source.num_frames - 1).astype(int)
    changed = {p: c[to_human] for p, c in changed_h.items()}  # on the robot's frames (tempo, --fps)
    any_h = np.any(list(changed_h.values()), axis=0)
    q_edit, window = src.qpos.copy(), None
    if any_h.any():
        q_edit, window = edit_solution(edit, robot, _fixed_like(opts, src), src, any_h, blend_seconds + MARGIN_SECONDS)
    t_edit = time.perf_counter() - t0 - t_src
    parts = hinge_parts(robot)
    q_comp, weights = compose(src.qpos, q_edit, changed, parts, blend)
    qpos, need = q_comp, None
    if window is not None and window[1] - window[0] >= 2:
        def with_override(frames: list[int]) -> np.ndarray:
            must = np.zeros(t_r, bool)
            must[frames] = True
            return compose(src.qpos, q_edit, {p: c | must for p, c in changed.items()}, parts, blend)[0]

        need, q_over = must_override(robot, src, q_comp, q_edit, window, with_override, blend, balance_override)
        if need.frames and balance_override:
            qpos = q_over
    elapsed = time.perf_counter() - t0
    human = {p: {"frames": frame_ranges(np.flatnonzero(c)), "max_m": float(dev[p][c].max()),
                 "frames_changed": int(c.sum())} for p, c in changed_h.items() if c.any()}
    robot_diff = _moved(qpos, src.qpos, robot.joint_names)
    override = _override_info(need, balance_override, qpos, q_comp, robot.joint_names)
    info = {"tolerance_m": tolerance, "blend_frames": blend, "retargeted_window": window,
            "tempo": tempo, "robot_frames": t_r, "balance_override": override,
            "balance_override_frames": override["frames"] if override and override["applied"] else None,
            "frames": source.num_frames, "fps": source.fps, "parts": list(PARTS),
            "seconds": {"source": round(t_src, 3), "edit": round(t_edit, 3), "total": round(elapsed, 3)}}
    edited = RobotMotion(qpos, src.fps, src.joint_names, src.robot,
                         {**dict(src.meta), **{k: v for k, v in edit.meta.items() if k in ("source", "prompt", "clip")},
                          "edit": {"human_parts_changed": sorted(human), "source_weight_min": float(weights.min()),
                                   **info}})
    return EditResult(src, edited, human, robot_diff, info)

"""SMPL-family parameters -> canonical clips through a body model (:mod:`~motion2robot.motion.body_model`).

- MotionFix/OmniME SMPL-H outputs (T, 135): translation (3), then 22 6D rotations (global
  orientation, 21 body joints); z up, 30 fps.
- Their evaluation results: a pickled dict {'pose', 'pose_source', 'pose_target': (T, 135),
  'text'}; clips in that order (the edited result is clip 0), the instruction as prompt.
- AMASS .npz: 'poses' (T, 156 SMPL-H / 72 SMPL / 165 SMPL-X) axis-angle, 'trans', 'betas',
  'mocap_framerate' (or 'mocap_frame_rate'); SMPL-X files with 'root_orient' + 'pose_body'; z up.
- AIST++ .pkl: 'smpl_poses' (T, 72), 'smpl_trans' in AIST++ units (/ 'smpl_scaling'), y up, 60 fps.
Joints come from ``--body-model`` (the user's model file); without it, from the built-in
approximate skeleton with a one-line warning, or a refusal under ``--strict``.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from motion2robot.errors import InputWarning
from motion2robot.motion.body_model import approximate_model, joint_positions, load_body_model
from motion2robot.motion.canonical import canonicalize
from motion2robot.motion.checks import check_frames, fail
from motion2robot.motion.human import HumanMotion
from motion2robot.motion.options import ReadOptions
from motion2robot.motion.rotations import matrix_from_6d, matrix_from_axis_angle

MOTIONFIX_FPS = 30.0
AISTPP_FPS = 60.0
EDIT_KEYS = ("pose", "pose_source", "pose_target")
#: How far the built-in skeleton's joints are from a real body model's: an AIST++ clip read with it
#: against the same motion through the SMPL neutral skeleton (scripts/measure_formats.py).
APPROXIMATION = "joints 5 cm (up to 9 cm) from the SMPL neutral body's"


def body_for(path: Path, opts: ReadOptions, betas: Any = None):
    """(BodyModel, a sentence for meta) from --body-model, else the approximate skeleton."""
    if opts.body_model:
        return load_body_model(opts.body_model, None if betas is None else np.asarray(betas))
    if opts.strict:
        raise fail(path, "holds SMPL body-model parameters (rotations); turning them into joint positions "
                         "needs the licence-restricted SMPL/SMPL-H model files, which are not shipped, and "
                         "--strict refuses the built-in approximate skeleton",
                   "pass --body-model PATH (your SMPL-H/SMPL/SMPL-X model .npz), or drop --strict")
    warnings.warn(InputWarning(
        f"{path}: no --body-model given: joints from the built-in approximate skeleton (HumanML3D bone "
        f"lengths in a T-pose; {APPROXIMATION}); pass --body-model PATH for exact joints"), stacklevel=2)
    return approximate_model()


def _clip(path: Path, rot: np.ndarray, trans: np.ndarray, fps: float, up: str, opts: ReadOptions,
          fmt: str, clip: int, betas: Any = None, **meta: Any) -> HumanMotion:
    check_frames(path, np.concatenate([rot.reshape(rot.shape[0], -1), trans], axis=1), "parameters")
    model = body_for(path, opts, betas)
    pos = joint_positions(model, rot[:, :22], trans)
    return canonicalize(
        path, pos, opts.fps or fps, up=opts.up or up, up_source="--up" if opts.up else f"the format: {up} up",
        units=opts.units or "m", units_source="--units" if opts.units else "the format: metres",
        source_fps=fps, meta={"source": str(path), "format": fmt, "clip": clip, "body_model": model.source, **meta})


def _pick(path: Path, n: int, clip: int | None) -> list[int]:
    if clip is None:
        return list(range(n))
    if not -n <= clip < n:
        raise fail(path, f"has {n} clip(s), --clip {clip} is out of range", f"pass --clip between 0 and {n - 1}")
    return [clip % n]


def _rot135(path: Path, a: Any, what: str) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(a, dtype=np.float64) if isinstance(a, np.ndarray) else None
    if a is None or a.ndim != 2 or a.shape[1] != 135:
        raise fail(path, f"{what} has shape {getattr(a, 'shape', None)}, not SMPL-H rotations (T, 135)",
                   "give MotionFix/OmniME SMPL-H output: translation + 22 6D rotations per frame")
    return matrix_from_6d(a[:, 3:].reshape(-1, 22, 6)), a[:, :3]


def read_smplh_135(path: Path, arr: np.ndarray, opts: ReadOptions) -> list[HumanMotion]:
    """(T, 135) or (N, T, 135) SMPL-H rotations (MotionFix/OmniME), z up, 30 fps."""
    clips = [arr] if arr.ndim == 2 else list(arr) if arr.ndim == 3 else [arr]
    out = []
    for i in _pick(path, len(clips), opts.clip):
        rot, trans = _rot135(path, clips[i], "the array")
        out.append(_clip(path, rot, trans, MOTIONFIX_FPS, "z", opts, "smplh_135", i))
    return out


def read_edit_result(path: Path, obj: Any, opts: ReadOptions) -> list[HumanMotion]:
    """An editor's result dict: clips 'pose' (the edit), 'pose_source', 'pose_target' as present."""
    if not isinstance(obj, Mapping) or "pose" not in obj:
        raise fail(path, "is not an editor result dict with 'pose'", "give the MotionFix/OmniME result file")
    keys = [k for k in EDIT_KEYS if k in obj]
    text = obj.get("text")
    out = []
    for i in _pick(path, len(keys), opts.clip):
        rot, trans = _rot135(path, obj[keys[i]], f"'{keys[i]}'")
        role = {"pose": "edited", "pose_source": "source", "pose_target": "target"}[keys[i]]
        out.append(_clip(path, rot, trans, MOTIONFIX_FPS, "z", opts, "edit_result", i, role=role,
                         prompt=str(text) if text is not None else None))
    return out


def _axis_angle_body(path: Path, poses: np.ndarray) -> np.ndarray:
    if poses.ndim != 2 or poses.shape[1] < 66 or poses.shape[1] % 3:
        raise fail(path, f"'poses' has shape {poses.shape}, not axis-angle per joint (T, 3 x joints >= 66)",
                   "give AMASS/SMPL poses (T, 156), (T, 72) or (T, 165)")
    return matrix_from_axis_angle(poses[:, :66].reshape(-1, 22, 3))


def read_amass(path: Path, opts: ReadOptions) -> list[HumanMotion]:
    """AMASS SMPL-H / SMPL-X parameter .npz (z up)."""
    if opts.clip not in (None, 0, -1):
        raise fail(path, f"holds one clip, --clip {opts.clip} is out of range", "pass --clip 0 or omit it")
    from motion2robot.motion.archive import read_npz_members

    d = dict(read_npz_members(path, ("poses", "trans", "betas", "root_orient", "pose_body", "mocap_framerate",
                                     "mocap_frame_rate")))
    if "poses" in d:
        poses = np.asarray(d["poses"], dtype=np.float64)
    elif "root_orient" in d and "pose_body" in d:
        poses = np.concatenate([d["root_orient"], d["pose_body"]], axis=1).astype(np.float64)
    else:
        raise fail(path, "has neither 'poses' nor 'root_orient' + 'pose_body'", "give an AMASS/SMPL-X .npz")
    rot = _axis_angle_body(path, poses)
    trans = np.asarray(d.get("trans", np.zeros((len(poses), 3))), dtype=np.float64)
    if trans.shape != (len(poses), 3):
        raise fail(path, f"'trans' has shape {trans.shape}, expected ({len(poses)}, 3)", "re-export the file")
    rate = d.get("mocap_framerate", d.get("mocap_frame_rate"))
    if rate is None and opts.fps is None:
        raise fail(path, "has no 'mocap_framerate'", "pass --source-fps")
    fps = float(rate) if rate is not None else float(opts.fps)  # type: ignore[arg-type]
    fps = float(round(fps)) if abs(fps - round(fps)) < 1e-3 * fps else fps  # float32 120.00005 -> 120
    return [_clip(path, rot, trans, fps, "z", opts, "amass", 0, betas=d.get("betas"))]


def read_smpl_pkl(path: Path, opts: ReadOptions) -> list[HumanMotion]:
    """A pickle (restricted unpickler): AIST++ SMPL parameters, or an editor result dict."""
    from motion2robot.motion.safe_pickle import restricted_load

    with open(path, "rb") as fh:
        obj = restricted_load(path, fh)
    if isinstance(obj, Mapping) and "pose" in obj:
        return read_edit_result(path, obj, opts)
    if not (isinstance(obj, Mapping) and "smpl_poses" in obj):
        raise fail(path, f"holds a {type(obj).__name__}, not a known motion pickle", "pass --format")
    if opts.clip not in (None, 0, -1):
        raise fail(path, f"holds one clip, --clip {opts.clip} is out of range", "pass --clip 0 or omit it")
    poses = np.asarray(obj["smpl_poses"], dtype=np.float64)
    scale = float(np.asarray(obj.get("smpl_scaling", 1.0)).reshape(-1)[0])
    trans = np.asarray(obj.get("smpl_trans", np.zeros((len(poses), 3))), dtype=np.float64) / scale
    return [_clip(path, _axis_angle_body(path, poses), trans, AISTPP_FPS, "y", opts, "aistpp_smpl", 0)]

"""MotionFix / TMED / OmniME 207-d features -> joint positions, without any body model.

Per frame (z up, 30 fps), five groups in this order (:data:`GROUPS`):
0:3 body_transl_delta_pelv: v_i = R_{i-1}^T (t_i - t_{i-1}), v_0 = 0 (t: the body's translation);
3:9 body_orient_xy: the pelvis orientation with its rotation about z removed (6D);
9:15 z_orient_delta: D_i = Rz_{i-1}^T Rz_i (6D), D_0 = identity;
15:141 body_pose: 21 local joint rotations (6D; not needed for positions);
141:207 body_joints_local_wo_z_rot: p_rel = Rz_i^T (p - pelvis_i) for the 22 SMPL joints.
"6D" is the first two rows of a rotation matrix (:mod:`~motion2robot.motion.rotations`).
Decoding: Rz_0 = I, Rz_i = Rz_{i-1} D_i (its z part), R_i = Rz_i Rxy_i, t_0 = 0,
t_i = t_{i-1} + R_{i-1} v_i, p = t_i + Rz_i p_rel. The first frame's heading and the offset
between t and the pelvis are lost; the canonical frame (floor, heading, origin) removes both.

Reference checked: github.com/athn-nik/motionfix (the MotionFix authors' code) at commit
e681d40036156121507ff65629c9a46395a4191a, read, not copied. Matched: the group order
(configs/data/motionfix.yaml ``load_feats``); each group's definition (src/data/motionfix.py
``_get_body_transl_delta_pelv``: deltas in the previous frame's FULL pelvis rotation, first frame
zero; ``_get_body_orient_xy`` / ``get_z_rot`` in src/tools/transforms3d.py: the heading is the Z
angle of a ZYX Euler decomposition, so R = Rz Rxy; ``_get_z_orient_delta`` via ``rot_diff``:
R_{i-1}^T R_i, identity first; ``_get_body_joints_local_wo_z_rot``: Rz^T (p - pelvis joint)); 6D =
first two rows, Gram-Schmidt back (src/tools/geometry.py); the decoding in
src/model/base_diffusion.py ``diffout2motion`` (Rz_0 = I, Rz_i = Rz_{i-1} D_i, t_i = t_{i-1} +
R_{i-1} v_i); the statistics file deps/stats/statistics_motionfix.npy: a pickled dict of numpy
arrays only, one {"mean", "std", "min", "max"} per group plus "body_transl" (read by
:func:`load_stats`). Differences, none affecting joint positions after the canonical frame: their
decoder starts t at the statistics' ``body_transl`` mean (here 0); it re-extracts the heading from
the matrix product (here the heading angles are summed: the same for rotations about z).
Their statistics show the conventions: mean ``body_orient_xy`` ~ Rx(90 deg) (SMPL's y-up body
stood up in z-up AMASS), so in the heading frame the body faces -y with its left hip at +x.

Models working in normalised space write normalised features; the MotionFix model's own output is
(x - mean) / (2 (std + 1e-5)) (src/model/base.py ``norm``, "standardize"), its data module writes
(x - mean) / (std + 1e-5), other code (x - mean) / std: :func:`raw_features` tries the three and
keeps the one whose 6D rows come out orthonormal. The statistics file is a pickled dict read with
the restricted unpickler: {"mean": (207,), "std": (207,)} or one {"mean", "std"} entry per group
name (extra keys such as "min", "max", "body_transl" are ignored).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np

from motion2robot.motion.canonical import canonicalize
from motion2robot.motion.checks import check_frames, fail
from motion2robot.motion.human import HumanMotion
from motion2robot.motion.options import ReadOptions
from motion2robot.motion.rotations import matrix_from_6d, rot_z, yaw_of

DIM = 207
FPS = 30.0
#: (name, slice) of the five feature groups.
GROUPS: tuple[tuple[str, slice], ...] = (
    ("body_transl_delta_pelv", slice(0, 3)), ("body_orient_xy", slice(3, 9)),
    ("z_orient_delta", slice(9, 15)), ("body_pose", slice(15, 141)),
    ("body_joints_local_wo_z_rot", slice(141, 207)),
)
_ROTATIONS = slice(3, 141)  # 23 6D blocks: orientation, heading change, 21 joint rotations


def decode_positions(feat: np.ndarray) -> np.ndarray:
    """(T, 207) raw features -> (T, 22, 3) joint positions, z up, metres (start at the origin)."""
    f = np.asarray(feat, dtype=np.float64)
    t = f.shape[0]
    rxy = matrix_from_6d(f[:, 3:9])
    d_yaw = yaw_of(matrix_from_6d(f[:, 9:15]))
    d_yaw[0] = 0.0
    rz = rot_z(np.cumsum(d_yaw))
    r = rz @ rxy
    steps = np.einsum("tij,tj->ti", r[:-1], f[1:, 0:3])
    trans = np.zeros((t, 3))
    trans[1:] = np.cumsum(steps, axis=0)
    rel = f[:, 141:207].reshape(t, 22, 3)
    return trans[:, None, :] + np.einsum("tij,tkj->tki", rz, rel)


def looks_raw(feat: np.ndarray) -> bool:
    """True when every 6D block holds two orthonormal rows (raw features; normalised ones do not)."""
    rows = np.asarray(feat, dtype=np.float64)[..., _ROTATIONS].reshape(*np.shape(feat)[:-1], 23, 2, 3)
    norms = np.linalg.norm(rows, axis=-1)
    dots = np.sum(rows[..., 0, :] * rows[..., 1, :], axis=-1)
    return bool(np.all(np.abs(norms - 1.0) < 1e-3) and np.all(np.abs(dots) < 1e-3))


def stats_arrays(path: str | Path, obj: Any) -> tuple[np.ndarray, np.ndarray]:
    """(mean, std), 207 values each, from a statistics dict (flat or per group)."""
    if not isinstance(obj, Mapping):
        raise fail(path, f"holds a {type(obj).__name__}, not a statistics dict",
                   "give the model's statistics file (a dict of mean/std)")
    if "mean" in obj and "std" in obj:
        mean, std = (np.asarray(obj[k], dtype=np.float64).reshape(-1) for k in ("mean", "std"))
    elif all(name in obj for name, _ in GROUPS):
        try:
            mean = np.concatenate([np.asarray(obj[n]["mean"], dtype=np.float64).reshape(-1) for n, _ in GROUPS])
            std = np.concatenate([np.asarray(obj[n]["std"], dtype=np.float64).reshape(-1) for n, _ in GROUPS])
        except (KeyError, TypeError, IndexError, ValueError):
            raise fail(path, "has per-group entries without numeric 'mean'/'std'",
                       "give the model's statistics file unchanged") from None
    else:
        keys = ", ".join(sorted(map(str, obj))[:8])
        raise fail(path, f"has keys {keys}: neither 'mean'/'std' nor the five 207-d group names",
                   "give the statistics file the MotionFix/OmniME model was trained with")
    if mean.shape != (DIM,) or std.shape != (DIM,):
        raise fail(path, f"holds statistics of {mean.size} / {std.size} values, the 207-d features need {DIM}",
                   "give the statistics of the 207-d representation (not of another model)")
    if not (np.isfinite(mean).all() and np.isfinite(std).all()):
        raise fail(path, "holds non-finite statistics", "re-export the statistics file")
    return mean, std


def load_stats(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a statistics file (.npy holding a pickled dict, or a .pkl) with the restricted unpickler."""
    from motion2robot.motion.safe_pickle import load_npy, restricted_load

    path = Path(path)
    if not path.is_file():
        raise fail(path, "--stats file not found", "give the model's statistics file")
    with open(path, "rb") as fh:
        magic = fh.read(6)
    if magic == b"\x93NUMPY":
        obj = load_npy(path)
    else:
        with open(path, "rb") as fh:
            obj = restricted_load(path, fh)
    return stats_arrays(path, obj)


#: Denormalisations the MotionFix code uses, tried in this order (x: normalised; eps = 1e-5):
#: the model's "standardize" (its diffusion output), the data module's "std", and plain mean/std.
DENORMALISATIONS: tuple[tuple[str, float, float], ...] = (
    ("x * 2 (std + 1e-5) + mean (the MotionFix model's standardisation)", 2.0, 1e-5),
    ("x * (std + 1e-5) + mean (the MotionFix data module's)", 1.0, 1e-5),
    ("x * std + mean", 1.0, 0.0),
)


def _orthonormal_residual(feat: np.ndarray) -> float:
    rows = np.asarray(feat, dtype=np.float64)[..., _ROTATIONS].reshape(*np.shape(feat)[:-1], 23, 2, 3)
    norms = np.abs(np.linalg.norm(rows, axis=-1) - 1.0).max()
    dots = np.abs(np.sum(rows[..., 0, :] * rows[..., 1, :], axis=-1)).max()
    return float(max(norms, dots))


def raw_features(path: Path, feat: np.ndarray, stats: tuple[np.ndarray, np.ndarray] | None,
                 stats_name: str = "--stats") -> tuple[np.ndarray, str]:
    """Raw features and a sentence saying what was assumed. Normalised input is denormalised with
    each of :data:`DENORMALISATIONS`; the one whose 6D rows come out orthonormal (the smallest
    residual) is used."""
    if looks_raw(feat):
        return feat, "raw (6D rotations orthonormal)" + ("; statistics not applied" if stats else "")
    if stats is None:
        raise fail(path, "looks like normalised 207-d features (its 6D rotation rows are not orthonormal) "
                         "and no statistics were given", "pass --stats STATS of the model (its mean/std dict)")
    mean, std = stats
    tries = [(feat * (k * (std + eps)) + mean, what) for what, k, eps in DENORMALISATIONS]
    raw, what = min(tries, key=lambda t: _orthonormal_residual(t[0]))
    if not looks_raw(raw):
        raise fail(path, f"does not become raw features with the statistics of {stats_name} "
                         "(its 6D rotation rows are still not orthonormal)",
                   "give the statistics file of the model that wrote these features")
    return raw, f"normalised, denormalised with {stats_name} as {what}"


def features_to_clips(path: Path, arr: np.ndarray, opts: ReadOptions,
                      stats: tuple[np.ndarray, np.ndarray] | None = None, stats_name: str = "--stats"
                      ) -> list[HumanMotion]:
    """(T, 207) or (N, T, 207) -> canonical clips (z up, metres, 30 fps unless --source-fps)."""
    from motion2robot.motion.read_arrays import _pick

    if arr.ndim not in (2, 3) or arr.shape[-1] != DIM:
        raise fail(path, f"has shape {arr.shape}, not MotionFix/OmniME features (T, {DIM})",
                   f"give {DIM}-d features per frame, or pass the right --format")
    feat = np.asarray(arr, dtype=np.float64)
    clips = [feat] if feat.ndim == 2 else list(feat)
    out = []
    for i, f in _pick(clips, opts.clip, path):
        check_frames(path, f, "features")
        raw, assumed = raw_features(path, f, stats, stats_name)
        out.append(canonicalize(
            path, decode_positions(raw), opts.fps or FPS, up=opts.up or "z",
            up_source="--up" if opts.up else "the format: MotionFix features are z up",
            units=opts.units or "m", units_source="--units" if opts.units else "the format: metres",
            source_fps=FPS, meta={"source": str(path), "format": "motionfix_207", "clip": i, "features": assumed}))
    return out


def read_motionfix(path: Path, arr: Any, opts: ReadOptions) -> list[HumanMotion]:
    """A .npy of 207-d features, raw or normalised with ``opts.stats``."""
    stats = load_stats(opts.stats) if opts.stats else None
    return features_to_clips(path, np.asarray(arr), opts, stats, str(opts.stats))

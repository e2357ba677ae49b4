"""Operations on :class:`HumanMotion`: resample, trim, floor and heading alignment, mirror.

All return new motions (HumanMotion is immutable); positions stay in metres, z up.
"""

from __future__ import annotations

import numpy as np

from motion2robot.motion.canonical import canonical_positions, floor_offset, heading_yaw, rot_z
from motion2robot.motion.human import KP, SMPL22, HumanMotion

#: Index permutation swapping left and right SMPL22 joints.
MIRROR_INDEX = tuple(
    KP[n.replace("left_", "right_")] if n.startswith("left_")
    else KP[n.replace("right_", "left_")] if n.startswith("right_") else i
    for i, n in enumerate(SMPL22)
)


def catmull_rom(values: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Cubic (Catmull-Rom) interpolation of samples (T, ...) at fractional indices u in [0, T-1].

    Passes through every sample; end tangents use linearly extrapolated ghost samples."""
    v = np.asarray(values, dtype=np.float64)
    t = v.shape[0]
    if t < 2:
        return np.repeat(v[:1], len(u), axis=0)
    ext = np.concatenate([2 * v[:1] - v[1:2], v, 2 * v[-1:] - v[-2:-1]], axis=0)
    i = np.clip(np.floor(u).astype(np.int64), 0, t - 2)
    s = (u - i).reshape(-1, *([1] * (v.ndim - 1)))
    p0, p1, p2, p3 = ext[i], ext[i + 1], ext[i + 2], ext[i + 3]
    return 0.5 * (2 * p1 + (p2 - p0) * s + (2 * p0 - 5 * p1 + 4 * p2 - p3) * s ** 2
                  + (3 * p1 - p0 - 3 * p2 + p3) * s ** 3)


def spline(values: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Natural cubic spline of samples (T, ...) at fractional indices u in [0, T-1]: through every
    sample, continuous in value, slope and curvature (C2; Catmull-Rom is only C1, so a finer rate
    reveals its curvature jumps at the samples as acceleration spikes), zero curvature at the ends.
    The knot curvatures solve the tridiagonal system M[i-1] + 4 M[i] + M[i+1] = 6 (second
    difference at i) by the Thomas algorithm, vectorised over the trailing axes."""
    v = np.asarray(values, dtype=np.float64)
    T = v.shape[0]
    if T < 3:
        return linear(v, u) if T == 2 else np.repeat(v[:1], len(u), axis=0)
    rhs = 6.0 * (v[2:] - 2.0 * v[1:-1] + v[:-2])          # (T-2, ...)
    n = T - 2
    c = np.empty(n)
    d = np.empty_like(rhs)
    c[0], d[0] = 0.25, rhs[0] / 4.0
    for i in range(1, n):
        den = 4.0 - c[i - 1]
        c[i] = 1.0 / den
        d[i] = (rhs[i] - d[i - 1]) / den
    M = np.zeros_like(v)
    M[n] = d[n - 1]
    for i in range(n - 2, -1, -1):
        M[i + 1] = d[i] - c[i] * M[i + 2]
    i = np.clip(np.floor(u).astype(np.int64), 0, T - 2)
    t = (u - i).reshape(-1, *([1] * (v.ndim - 1)))
    a = 1.0 - t
    return a * v[i] + t * v[i + 1] + ((a ** 3 - a) * M[i] + (t ** 3 - t) * M[i + 1]) / 6.0


def linear(values: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Linear interpolation of samples (T, ...) at fractional indices u in [0, T-1]."""
    v = np.asarray(values, dtype=np.float64)
    i = np.clip(np.floor(u).astype(np.int64), 0, max(v.shape[0] - 2, 0))
    s = (u - i).reshape(-1, *([1] * (v.ndim - 1)))
    j = np.minimum(i + 1, v.shape[0] - 1)
    return v[i] * (1 - s) + v[j] * s


def resample(m: HumanMotion, fps: float, kind: str = "cubic") -> HumanMotion:
    """Resample to ``fps`` over the same time span [0, (T-1)/fps_old]. Positions: "cubic"
    (natural cubic spline, C2, through every original frame: :func:`spline`) or "linear";
    contacts: nearest frame."""
    if not fps > 0:
        raise ValueError(f"fps must be positive, got {fps}")
    if kind not in ("cubic", "linear"):
        raise ValueError(f"kind must be 'cubic' or 'linear', got {kind!r}")
    n = int(np.floor((m.num_frames - 1) * fps / m.fps + 1e-9)) + 1
    u = np.arange(n) * (m.fps / fps)
    pos = (spline if kind == "cubic" else linear)(m.positions, u)
    contacts = None if m.contacts is None else m.contacts[np.clip(np.rint(u).astype(int), 0, m.num_frames - 1)]
    return m.with_(positions=pos, fps=fps, contacts=contacts, meta={"resampled_from_fps": m.fps})


def trim(m: HumanMotion, start: int, stop: int | None = None) -> HumanMotion:
    """Frames [start, stop) (Python slice semantics); positions are not re-aligned."""
    sl = slice(start, stop)
    idx = range(m.num_frames)[sl]
    if len(idx) < 2:
        raise ValueError(f"trim({start}, {stop}) leaves {len(idx)} frames of {m.num_frames}; need at least 2")
    contacts = None if m.contacts is None else m.contacts[sl]
    return m.with_(positions=m.positions[sl], contacts=contacts,
                   meta={"trimmed": [idx.start, idx.stop]})


def align_floor(m: HumanMotion) -> HumanMotion:
    """Shift along z so the lowest foot keypoint (ankles, toes) over the clip is at z = 0."""
    pos = m.positions.copy()
    pos[..., 2] -= floor_offset(pos)
    return m.with_(positions=pos)


def align_heading(m: HumanMotion) -> HumanMotion:
    """Rotate about z so frame 0 faces +x, and shift so the pelvis is over the origin at frame 0
    (also re-applies the floor alignment)."""
    return m.with_(positions=canonical_positions(m.positions))


def rotate_heading(m: HumanMotion, yaw: float) -> HumanMotion:
    """Rotate the whole motion by ``yaw`` radians about the z axis through the origin."""
    return m.with_(positions=m.positions @ rot_z(yaw).T)


def facing_yaw(m: HumanMotion, frame: int = 0) -> float:
    """Yaw (rad) the subject faces at ``frame`` (0 for a canonical motion's frame 0)."""
    return heading_yaw(m.positions, frame)


def mirror(m: HumanMotion) -> HumanMotion:
    """Left/right mirror image: y -> -y and left/right keypoints (and contact columns) swapped.
    Frame 0 still faces +x."""
    pos = m.positions[:, list(MIRROR_INDEX)].copy()
    pos[..., 1] *= -1.0
    contacts = None if m.contacts is None else m.contacts[:, ::-1]
    return m.with_(positions=pos, contacts=contacts, meta={"mirrored": not m.meta.get("mirrored", False)})

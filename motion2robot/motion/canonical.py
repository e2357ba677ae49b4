"""One conversion from a reader's raw joint positions into the canonical frame.

Canonical frame (see :class:`~motion2robot.motion.human.HumanMotion`): z up, x forward at
frame 0 (the subject faces +x, its left is +y), metres, floor at z = 0, pelvis above the
origin at frame 0.

Steps, in order: up axis (given, fixed by the format, or detected from head-above-feet), a
right-handed rotation taking it to +z, units (given, fixed by the format, or detected from the
skeleton's size), a sanity bound on the subject's height, floor at the lowest foot keypoint,
heading about z so frame 0 faces +x. Each decision is written into ``meta``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np

from motion2robot.motion.checks import check_fps, check_frames, check_magnitude, fail, numeric_positions
from motion2robot.motion.height import stature
from motion2robot.motion.plausibility import warn_implausible
from motion2robot.motion.human import KP, SMPL22, HumanMotion

#: Foot keypoints used for the floor and contacts: ankles and toes.
FOOT_KPS = (KP["left_ankle"], KP["right_ankle"], KP["left_foot"], KP["right_foot"])

#: metres per unit.
UNIT_SCALE: dict[str, float] = {
    "m": 1.0, "cm": 0.01, "mm": 0.001, "inch": 0.0254,
    "cmu": 0.0254 / 0.45,  # CMU mocap units: 1/0.45 inch = 5.644 cm
}
#: Raw-stature windows for unit auto-detection (in the file's own units).
AUTO_UNIT_RANGES: tuple[tuple[str, float, float], ...] = (
    ("m", 0.3, 3.5), ("cmu", 12.0, 45.0), ("inch", 45.0, 100.0), ("cm", 100.0, 350.0),
    ("mm", 500.0, 3500.0),
)
#: Plausible subject heights after conversion, metres (children to tall adults, with margin).
HEIGHT_BOUNDS = (0.5, 3.0)

_FOOT_IDX = np.array(FOOT_KPS, dtype=np.intp)
_AXES = {"x": 0, "y": 1, "z": 2}


def detect_up(positions: np.ndarray) -> tuple[str, float]:
    """Up axis ("x"|"y"|"z", possibly "-"-prefixed) from head-above-feet, and the fraction of
    frames agreeing with it."""
    d = positions[:, KP["head"]] - positions[:, list(FOOT_KPS)].mean(axis=1)
    med = np.median(d, axis=0)
    a = int(np.argmax(np.abs(med)))
    sign = 1.0 if med[a] >= 0 else -1.0
    agree = (np.argmax(np.abs(d), axis=1) == a) & (np.sign(d[:, a]) == sign)
    name = "xyz"[a] if sign > 0 else "-" + "xyz"[a]
    return name, float(agree.mean())


def up_rotation(up: str) -> np.ndarray:
    """Proper rotation (3x3) taking the axis ``up`` ("x", "y", "z", "-x", ...) to +z.

    +y up maps (x, y, z) -> (z, x, y): a y-up subject facing +z with its left at +x ends up facing
    +x with its left at +y (the HumanML3D convention lands exactly on the canonical one).
    """
    neg = up.startswith("-")
    a = _AXES[up.lstrip("-+")]
    perm = {0: (1, 2, 0), 1: (2, 0, 1), 2: (0, 1, 2)}[a]  # new axis i takes old axis perm[i]
    r = np.zeros((3, 3))
    for i, j in enumerate(perm):
        r[i, j] = 1.0
    if neg:  # half turn about the new x axis flips z (and y), keeping the frame right-handed
        r = np.diag([1.0, -1.0, -1.0]) @ r
    return r


def detect_units(raw_stature: float) -> str | None:
    """Unit name whose window holds the raw stature, or None."""
    for name, lo, hi in AUTO_UNIT_RANGES:
        if lo <= raw_stature < hi:
            return name
    return None


def floor_offset(positions: np.ndarray) -> float:
    """Height of the floor: the lowest foot keypoint (ankles, toes) over the whole clip."""
    return float(positions[:, _FOOT_IDX, 2].min())


def heading_yaw(positions: np.ndarray, frame: int = 0) -> float:
    """Yaw (rad, about +z) the subject faces at ``frame``, from the hip and shoulder left-right
    vectors (forward = left x up)."""
    p = positions[frame]
    left = (p[KP["left_hip"]] - p[KP["right_hip"]]) + (p[KP["left_shoulder"]] - p[KP["right_shoulder"]])
    if np.hypot(left[0], left[1]) < 1e-9:  # degenerate frame: average over the clip
        q = positions
        left = ((q[:, KP["left_hip"]] - q[:, KP["right_hip"]])
                + (q[:, KP["left_shoulder"]] - q[:, KP["right_shoulder"]])).mean(axis=0)
    return float(np.arctan2(-left[0], left[1]))  # forward = (left_y, -left_x)


def rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rotate(positions: np.ndarray, r: np.ndarray) -> np.ndarray:
    """``positions @ r.T`` for (..., 3) points as one (N, 3) @ (3, 3) product with a C-ordered
    right factor: the same values (tests/test_motion_fast_read.py checks), one BLAS call instead
    of a slow strided loop per frame."""
    p = np.ascontiguousarray(positions)
    return (p.reshape(-1, 3) @ np.ascontiguousarray(r.T)).reshape(p.shape)


def canonical_positions(positions: np.ndarray) -> np.ndarray:
    """z-up metres -> floor at z = 0, facing +x at frame 0, pelvis over the origin at frame 0."""
    return _canonical_positions_inplace(positions.copy())


def _canonical_positions_inplace(p: np.ndarray, steps: dict | None = None) -> np.ndarray:
    """:func:`canonical_positions` overwriting ``p`` (a float array the caller owns); ``steps``
    (optional) receives the floor height, the yaw turned and the pelvis offset removed."""
    # One strided column at a time: numpy runs a single long inner loop per column instead of one
    # short loop per point for a (T, 22, 2) slice (same values).
    floor = floor_offset(p)
    p[..., 2] -= floor
    yaw = heading_yaw(p)
    p = _rotate(p, rot_z(-yaw))
    px, py = p[0, KP["pelvis"], :2]
    p[..., 0] -= px
    p[..., 1] -= py
    if steps is not None:
        steps.update(floor=float(floor), yaw=float(yaw), origin=(float(px), float(py)))
    return p


def to_canonical(transform: Mapping[str, Any], points: np.ndarray) -> np.ndarray:
    """Points (..., 3) in a file's own axes and units -> the canonical frame of a clip read from it,
    with the clip's ``meta["canonical_transform"]`` (p_canonical = matrix @ p + offset)."""
    a = np.asarray(transform["matrix"], dtype=np.float64)
    return np.asarray(points, dtype=np.float64) @ a.T + np.asarray(transform["offset"], dtype=np.float64)


def canonicalize(path: str | Path, positions: np.ndarray, fps: float, *, up: str | None,
                 up_source: str, units: str | None, units_source: str,
                 contacts: np.ndarray | None = None,
                 meta: Mapping[str, Any] | None = None, source_fps: float | None = None) -> HumanMotion:
    """Raw (T, 22, 3) positions in the file's axes and units -> canonical :class:`HumanMotion`.

    up / units: None to detect; ``*_source`` says where a given value came from ("format",
    "--up", ...) and is recorded in meta; source_fps: the file's own rate when ``fps`` overrides it.
    """
    pos = numeric_positions(path, positions)
    fps = check_fps(path, fps, "the frame rate")
    check_frames(path, pos)
    check_magnitude(path, pos, SMPL22 if pos.ndim == 3 and pos.shape[1] == len(SMPL22) else None)
    if up is None:
        up, agree = detect_up(pos)
        up_source = f"detected: head above feet along {up} in {agree:.0%} of frames"
    pos = _rotate(pos, up_rotation(up))
    raw = stature(pos)
    if units is None:
        units = detect_units(raw)
        if units is None:
            raise fail(path, f"the skeleton is {raw:.4g} units tall, which fits none of m, cm, mm, "
                             "inch, CMU units (units?)", "pass --units m|cm|mm|inch|cmu")
        units_source = f"detected from the skeleton's size ({raw:.3g} units tall)"
    if units not in UNIT_SCALE:
        raise fail(path, f"unknown units {units!r}", f"use one of {', '.join(UNIT_SCALE)}")
    if UNIT_SCALE[units] != 1.0:  # x * 1.0 == x: skip the copy for metres
        pos = pos * UNIT_SCALE[units]
    height = raw * UNIT_SCALE[units]
    lo, hi = HEIGHT_BOUNDS
    if not lo <= height <= hi:
        raise fail(path, f"the subject is {height:.3g} m tall when read as {units} "
                         f"(expected {lo}-{hi} m; units?)",
                   "pass the right --units (m, cm, mm, inch, cmu) or --up if the skeleton lies on its side")
    steps: dict = {}
    pos = _canonical_positions_inplace(pos, steps)  # pos is our own array (made by _rotate)
    warn_implausible(path, pos, fps)
    matrix = rot_z(-steps["yaw"]) @ up_rotation(up) * UNIT_SCALE[units]
    offset = [-steps["origin"][0], -steps["origin"][1], -steps["floor"]]
    info = {"up_axis": up, "up_axis_source": up_source, "units": units, "units_source": units_source,
            "source_fps": float(source_fps or fps),
            "canonical_transform": {"matrix": matrix.tolist(), "offset": offset}}
    return HumanMotion(pos, fps, contacts=contacts, meta={**(meta or {}), **info})

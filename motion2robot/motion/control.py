"""The trajectory a controllable generator was asked to follow, in the clip's canonical frame.

Sources: OmniControl's ``hint`` in its results file ((N, T, 22, 3) in the motion's own space, zero
where a joint is not controlled; can be an empty list), or ``--trajectory FILE``: a (T, 3) root path,
or (T, 2) on the ground, in the motion file's own axes and units ((T, 2) columns are the two ground
axes in x, y, z order: x and z for a y-up file). Stored as ``meta["control_path"]``: per frame
[x, y, z] metres in the canonical frame (z None for a ground path), or None where not controlled.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from motion2robot.motion.canonical import to_canonical
from motion2robot.motion.checks import fail
from motion2robot.motion.human import HumanMotion

_FIX = "give a (T, 2) or (T, 3) root path, one row per frame of the motion, in the motion file's axes and units"


def path_meta(points: np.ndarray, ground_only: bool) -> list[list[float | None] | None]:
    """(T, 3) canonical points with NaN rows where uncontrolled -> the JSON-able meta list."""
    out: list[list[float | None] | None] = []
    for p in points:
        if not np.isfinite(p[:2]).all():
            out.append(None)
        else:
            out.append([float(p[0]), float(p[1]), None if ground_only else float(p[2])])
    return out


def from_hint(m: HumanMotion, hint: Any) -> HumanMotion:
    """Attach the pelvis track of an OmniControl hint ((T', 22, 3) raw, zero = not controlled)."""
    h = np.asarray(hint, dtype=np.float64) if isinstance(hint, np.ndarray) else None
    if h is None or h.ndim != 3 or h.shape[1:] != (22, 3) or not np.any(h):
        return m
    t = min(m.num_frames, h.shape[0])
    pel = np.full((m.num_frames, 3), np.nan)
    track = h[:t, 0]
    on = np.any(track != 0.0, axis=1)
    if not on.any():
        joints = sorted({int(j) for j in np.flatnonzero(np.any(h != 0.0, axis=(0, 2)))})
        return m.with_(meta={"control_note": f"the hint controls joints {joints}, not the pelvis: no root path"})
    pel[:t][on] = to_canonical(m.meta["canonical_transform"], track[on])
    return m.with_(meta={"control_path": path_meta(pel, False), "control_source": "hint (pelvis)"})


def load_trajectory(path: str | Path) -> np.ndarray:
    """A (T, 2) or (T, 3) array from .npy (numbers only), .csv or .txt."""
    path = Path(path)
    if not path.is_file():
        raise fail(path, "--trajectory file not found", _FIX)
    try:
        if path.suffix.lower() == ".npy":
            from motion2robot.motion.safe_pickle import load_npy

            arr = load_npy(path)
        else:
            arr = np.loadtxt(path, delimiter="," if path.suffix.lower() == ".csv" else None, ndmin=2)
        arr = np.asarray(arr, dtype=np.float64)
    except (ValueError, TypeError) as err:
        raise fail(path, f"is not a numeric table ({err})", _FIX) from None
    if arr.ndim != 2 or arr.shape[1] not in (2, 3) or arr.shape[0] < 2 or not np.isfinite(arr).all():
        raise fail(path, f"has shape {arr.shape}{'' if np.isfinite(arr).all() else ' with NaN/inf'}, "
                         "not a root path (T, 2) or (T, 3)", _FIX)
    return arr


def from_trajectory(m: HumanMotion, path: str | Path, arr: np.ndarray) -> HumanMotion:
    """Attach a --trajectory path (rows = the clip's frames as read from the file)."""
    if arr.shape[0] != m.num_frames:
        raise fail(path, f"has {arr.shape[0]} rows, the motion has {m.num_frames} frames", _FIX)
    ground = arr.shape[1] == 2
    pts = arr
    if ground:
        up = "xyz".index(str(m.meta.get("up_axis", "z")).lstrip("-+"))
        pts = np.zeros((arr.shape[0], 3))
        pts[:, [a for a in range(3) if a != up]] = arr
    canon = to_canonical(m.meta["canonical_transform"], pts)
    return m.with_(meta={"control_path": path_meta(canon, ground), "control_source": f"--trajectory {Path(path).name}"})

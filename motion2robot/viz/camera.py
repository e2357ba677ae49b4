"""Camera placement for rendering and viewing: ``follow`` (tracks the subjects) or ``fixed``.

Pure functions on (T, 3) point tracks (metres, world frame, z up); :func:`apply` copies one
frame's pose into a ``mujoco.MjvCamera`` (free camera: lookat, distance, azimuth, elevation in
degrees; azimuth 165 looks at a robot facing +x from the front, slightly from its right).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

MODES = ("follow", "fixed")


@dataclass(frozen=True)
class CameraTrack:
    """Per-frame camera: lookat (T, 3) m, distance (T,) m, fixed azimuth/elevation (degrees)."""

    lookat: np.ndarray
    distance: np.ndarray
    azimuth: float = 165.0
    elevation: float = -12.0

    def apply(self, cam: mujoco.MjvCamera, frame: int) -> None:
        f = min(max(frame, 0), len(self.distance) - 1)
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        cam.lookat[:] = self.lookat[f]
        cam.distance = float(self.distance[f])
        cam.azimuth = self.azimuth
        cam.elevation = self.elevation


def smooth(x: np.ndarray, window: int) -> np.ndarray:
    """Centred moving average along axis 0 (edges padded with the end values)."""
    if window <= 1 or len(x) < 2:
        return np.array(x, dtype=float)
    k = np.ones(window) / window
    pad = window // 2
    xp = np.concatenate([np.repeat(x[:1], pad, 0), x, np.repeat(x[-1:], window - 1 - pad, 0)])
    return np.stack([np.convolve(xp[:, j], k, mode="valid") for j in range(x.shape[1])], axis=1)


def fit_distance(half_width: float, half_height: float, fovy_deg: float = 45.0, aspect: float = 4 / 3,
                 margin: float = 1.25) -> float:
    """Distance at which a box of the given half extents (m) fills the view with ``margin``."""
    t = math.tan(math.radians(fovy_deg) / 2)
    return margin * max(half_height / t, half_width / (t * aspect))


def camera_track(tracks: list[np.ndarray], height: float, fps: float, mode: str = "follow",
                 fovy_deg: float = 45.0, aspect: float = 4 / 3) -> CameraTrack:
    """Camera following (or framing the whole path of) the subjects.

    tracks: (T, 3) ground points of each subject (robot root, human pelvis); height: the
    subjects' height (m), used for the vertical framing and the lookat height."""
    if mode not in MODES:
        raise ValueError(f"camera mode must be one of {MODES}, got {mode!r}")
    pts = np.stack([np.asarray(t, dtype=float)[:, :2] for t in tracks], axis=1)  # (T, S, 2)
    T = pts.shape[0]
    body = 0.35 * height  # half width of a body with arms
    if mode == "follow":
        centre = smooth(pts.mean(axis=1), max(1, int(round(fps))))
        spread = np.max(np.linalg.norm(pts - pts.mean(axis=1, keepdims=True), axis=2), axis=1)
        half_w = spread.max() + body
        lookat = np.column_stack([centre, np.full(T, 0.5 * height)])
        dist = np.full(T, fit_distance(half_w, 0.62 * height, fovy_deg, aspect))
        return CameraTrack(lookat, dist)
    lo, hi = pts.reshape(-1, 2).min(axis=0), pts.reshape(-1, 2).max(axis=0)
    centre = (lo + hi) / 2
    half_w = 0.5 * float(np.linalg.norm(hi - lo)) + body
    d = fit_distance(half_w, 0.62 * height, fovy_deg, aspect)
    return CameraTrack(np.tile([*centre, 0.5 * height], (T, 1)), np.full(T, d))

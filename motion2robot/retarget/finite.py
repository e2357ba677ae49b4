"""Nothing non-finite leaves the retargeting: the targets going in and the trajectory coming out
are checked, and a failure names the frame and the keypoint or joint (one-line SolverError)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motion2robot.errors import SolverError

#: Scaled keypoints farther than this from the origin (metres) are no body: 10 km.
MAX_TARGET_M = 1e4


def check_targets(kp: np.ndarray, names: Sequence[str], where: str) -> None:
    """(T, K, 3) scaled keypoint targets (metres): finite and within :data:`MAX_TARGET_M`."""
    bad = ~np.isfinite(kp) | (np.abs(np.nan_to_num(kp, nan=0.0, posinf=np.inf, neginf=np.inf)) > MAX_TARGET_M)
    if bad.any():
        t, k = (int(x) for x in np.argwhere(bad.any(axis=-1))[0])
        raise SolverError(f"{where}: frame {t}, keypoint {names[k] if k < len(names) else k} is at "
                          f"{kp[t, k].tolist()} m after scaling, which the solve cannot use (not finite or beyond "
                          f"{MAX_TARGET_M:g} m); fix or trim that frame in the source")


def check_solution(qpos: np.ndarray, joint_names: Sequence[str], where: str) -> None:
    """(T, 7 + n) solved trajectory: every value finite, else name the first bad frame and joint."""
    bad = ~np.isfinite(qpos)
    if bad.any():
        t, c = (int(x) for x in np.argwhere(bad)[0])
        what = "the root" if c < 7 else f"joint {joint_names[c - 7]}"
        raise SolverError(f"{where}: the solve went non-finite at frame {t}, {what} "
                          f"({int(bad.any(axis=1).sum())} frame(s) in all), from extreme values in the input near "
                          "that frame; fix or trim those frames in the source")

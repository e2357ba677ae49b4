"""Plausibility warnings on a canonical human motion (z up, metres): read, but worth a word.

Each finding is one :class:`~motion2robot.errors.InputWarning` line (the CLI prints
``motion2robot: warning: ...``; a batch keeps it in the row), never silence:

- upside down: the head below the pelvis in most frames (a flipped up axis the format implied);
- teleports: the pelvis jumps farther than :data:`TELEPORT_M` between two frames;
- absurd speeds: a keypoint faster than :data:`MAX_SPEED` relative to the pelvis (a thrown
  punch peaks near 10 m/s; this is a broken frame, not athletics).
Complex values with zero imaginary parts are reported where they are read
(:func:`~motion2robot.motion.checks.numeric_positions`).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from motion2robot.errors import InputWarning
from motion2robot.motion.human import KP, SMPL22

TELEPORT_M = 1.0
MAX_SPEED = 25.0
UPSIDE_DOWN_FRACTION = 0.5


def plausibility_findings(pos: np.ndarray, fps: float) -> list[str]:
    """Sentences about (T, 22, 3) canonical positions at ``fps`` (empty when nothing is odd)."""
    out = []
    head, pelvis = pos[:, KP["head"], 2], pos[:, KP["pelvis"], 2]
    down = float(np.mean(head < pelvis))
    if down > UPSIDE_DOWN_FRACTION:
        out.append(f"the body is upside down in {down:.0%} of frames (head below the pelvis); "
                   "pass --up with the file's real up axis if it is flipped")
    if pos.shape[0] >= 2:
        # squared distances compared with squared limits: no square root per keypoint and frame
        step = pos[1:] - pos[:-1]
        jump2 = np.einsum("tk,tk->t", step[:, KP["pelvis"]], step[:, KP["pelvis"]])
        k = int(np.argmax(jump2))
        if jump2[k] > TELEPORT_M ** 2:
            n = int(np.sum(jump2 > TELEPORT_M ** 2))
            out.append(f"the pelvis jumps {np.sqrt(jump2[k]):.3g} m between frames {k} and {k + 1} ({n} jump(s) over "
                       f"{TELEPORT_M:g} m in one frame): a teleport, not motion; trim or fix those frames")
        rel = step - step[:, KP["pelvis"]][:, None, :]  # the change of each keypoint relative to the pelvis
        speed2 = np.einsum("tjk,tjk->tj", rel, rel)
        t, j = np.unravel_index(int(np.argmax(speed2)), speed2.shape)
        speed = float(np.sqrt(speed2[t, j])) * fps
        if speed > MAX_SPEED:
            out.append(f"{SMPL22[j]} moves at {speed:.3g} m/s relative to the pelvis between frames {t} and "
                       f"{t + 1} (more than {MAX_SPEED:g} m/s): check the frame rate (--source-fps) or those frames")
    return out


def warn_implausible(path: str | Path, pos: np.ndarray, fps: float) -> None:
    """Issue one InputWarning per finding of :func:`plausibility_findings`."""
    for f in plausibility_findings(pos, fps):
        warnings.warn(InputWarning(f"{path}: {f}"), stacklevel=3)

"""The canonical human motion every reader produces and the retargeter consumes.

Frame: **z up, x forward at frame 0 (the subject faces +x), y to the subject's left, metres,
floor at z = 0**. Keypoints: the 22 SMPL body joints in HumanML3D order (:data:`SMPL22`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from motion2robot.util.frames import Frames

#: The 22 SMPL body joints in HumanML3D order.
SMPL22: tuple[str, ...] = (
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2",
    "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot", "neck",
    "left_collar", "right_collar", "head", "left_shoulder", "right_shoulder",
    "left_elbow", "right_elbow", "left_wrist", "right_wrist",
)
#: Parent of each SMPL22 joint (-1 for the pelvis).
SMPL22_PARENTS: tuple[int, ...] = (-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19)
KP = {name: i for i, name in enumerate(SMPL22)}


@dataclass(frozen=True, eq=False)
class HumanMotion(Frames):
    """A human motion clip in the canonical frame.

    positions: (T, 22, 3) float64, metres, z up, x forward at frame 0, floor at z = 0.
    fps: frames per second.
    contacts: optional (T, 2) bool, foot contact labels [left, right].
    meta: free-form JSON-serialisable facts (source, clip, prompt, format, ...).
    """

    positions: np.ndarray
    fps: float
    contacts: np.ndarray | None = None
    meta: Mapping[str, Any] = field(default_factory=dict)

    _frames_field = "positions"  # not a field (no annotation): the array whose rows are the frames

    def __post_init__(self) -> None:
        pos = np.asarray(self.positions, dtype=np.float64)
        if pos.ndim != 3 or pos.shape[1:] != (len(SMPL22), 3):
            raise ValueError(f"positions must be (T, 22, 3), got {pos.shape}")
        pos = pos.copy()
        pos.flags.writeable = False
        object.__setattr__(self, "positions", pos)
        if self.contacts is not None:
            c = np.asarray(self.contacts, dtype=bool)
            if c.shape != (pos.shape[0], 2):
                raise ValueError(f"contacts must be (T, 2), got {c.shape}")
            c = c.copy()
            c.flags.writeable = False
            object.__setattr__(self, "contacts", c)
        if not self.fps > 0:
            raise ValueError(f"fps must be positive, got {self.fps}")
        self._freeze_rate_and_meta()

    def joint(self, name: str) -> np.ndarray:
        """(T, 3) trajectory of one SMPL22 keypoint by name."""
        return self.positions[:, KP[name]]

"""Contact phases of each foot, and the anchored sole placement of each phase.

Labels come from the motion (``HumanMotion.contacts``) or, when absent, from
:func:`motion2robot.motion.contacts.detect_contacts`. During a phase (a run of contact frames)
the sole is pinned: its four corners at one placement on the floor (z = 0), the placement being
where the unpinned solve put the sole (centre and yaw) in the phase's first frame, so the foot
lands where it can (the unpinned solve already respects the velocity limits) and stays there.
"""

from __future__ import annotations

import numpy as np

from motion2robot.errors import SolverError
from motion2robot.motion.contacts import detect_contacts
from motion2robot.motion.human import KP, HumanMotion

#: m the human's ankle may be above its lowest level in a contact phase while the robot's flat
#: sole is planted (see :func:`planted`).
HEEL_LIFT = 0.02


def contact_labels(human: HumanMotion) -> tuple[np.ndarray, str]:
    """(T, 2) bool [left, right] and where they came from ("file" or "detected")."""
    if human.contacts is not None:
        labels, source = np.asarray(human.contacts, dtype=bool), "file"
    else:
        labels, source = detect_contacts(human), "detected"
    if not labels.any():
        where = human.meta.get("source", "the motion")
        raise SolverError(f"{where}: the feet never touch the floor (no contact frames, {source} labels); "
                          "retarget a motion that stands on the floor, or give contact labels")
    return labels, source


def planted(labels: np.ndarray, human: HumanMotion) -> np.ndarray:
    """The (T, 2) frames a flat robot sole is planted: each contact phase of ``labels`` without
    its leading and trailing frames in which the human's ankle is more than :data:`HEEL_LIFT`
    above its lowest level in the phase (the heel not down yet at landing; the heel up at
    toe-off, where the human stands on the toes only). A flat sole cannot roll over its toes: kept
    planted there, the trailing leg runs out of reach and the solver let the other, leading foot
    slide (op3, Xia walks at 120 fps: 12-14 % of the contact frames of a step)."""
    out = labels.copy()
    for f, a, b in phases(labels):
        z = human.positions[a:b, KP[("left_ankle", "right_ankle")[f]], 2]
        up = z - z.min() > HEEL_LIFT
        first = int(np.argmin(up))                     # first frame with the heel down
        last = len(up) - 1 - int(np.argmin(up[::-1]))  # last frame with the heel down
        out[a:a + first, f] = False
        out[a + last + 1:b, f] = False
    return out


def phases(labels: np.ndarray) -> list[tuple[int, int, int]]:
    """Runs of contact as (foot, first frame, last frame + 1)."""
    out = []
    for f in range(labels.shape[1]):
        x = np.concatenate([[False], labels[:, f], [False]]).astype(np.int8)
        d = np.diff(x)
        out.extend((f, int(a), int(b)) for a, b in zip(np.where(d == 1)[0], np.where(d == -1)[0]))
    return out


def yaw_rotation(yaw: np.ndarray | float) -> np.ndarray:
    """(..., 2, 2) the rotation by ``yaw`` (rad, ...) about z, in the horizontal plane."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def sole_yaw(corners: np.ndarray) -> np.ndarray:
    """Yaw (rad, in (-pi, pi]) of soles from their (..., 4, 3) corners (front-left, front-right,
    back-right, back-left): the direction from the back edge's midpoint to the front edge's."""
    xy = corners[..., :2]
    fwd = (xy[..., 0, :] + xy[..., 1, :]) - (xy[..., 2, :] + xy[..., 3, :])
    return np.arctan2(fwd[..., 1], fwd[..., 0])


def anchor_soles(corners: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Pinned sole corners (T, 2, 4, 3) for every contact frame (NaN elsewhere), from the sole
    corners ``corners`` (T, 2, 4, 3) of an unpinned solve: per phase, the centre and yaw of the
    sole in its first frame, the corners' mean layout about the centre (a rigid rectangle), at z = 0."""
    out = np.full(corners.shape, np.nan)
    xy = corners[..., :2]                                             # (T, 2, 4, 2)
    centre = xy.mean(axis=2)                                          # (T, 2, 2)
    yaw = sole_yaw(corners)                                           # (T, 2)
    rel = np.einsum("tfij,tfkj->tfki", yaw_rotation(-yaw), xy - centre[:, :, None])  # sole layouts, (T, 2, 4, 2)
    for f, a, b in phases(labels):
        layout = rel[a:b, f].mean(axis=0)
        out[a:b, f, :, :2] = centre[a, f] + layout @ yaw_rotation(yaw[a, f]).T
        out[a:b, f, :, 2] = 0.0
    return out

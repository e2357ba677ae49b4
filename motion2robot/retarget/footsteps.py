"""Feet that hold and lift: a target for every sole corner in every frame, from the contact schedule.

The human motion's contact schedule (per foot: phases on the floor, gaps in the air) becomes a
plan for each robot sole:

- **stance**: the four corners pinned at the phase's placement (centre and yaw where the unpinned
  solve put the sole in the phase's first frame, flat on the floor: :func:`~.contacts.anchor_soles`);
- **swing**: between two placements the sole lifts first, moves, then sets down:
  its height follows ``apex * 64 s^3 (1 - s)^3`` (s = 0..1 over the gap: zero speed and
  acceleration at lift-off and touch-down, ``apex`` at mid-swing) and its centre and yaw follow a
  minimum-jerk profile over the middle of the gap only (``s`` in [LIFT_LEAD, 1 - LIFT_LEAD]), so no
  point of the sole moves horizontally while it is near the floor. ``apex`` is the larger of
  ``APEX_RATIO`` times the robot's standing root height and the height the unpinned solve (which
  follows the human's foot) reached in that gap;
- **gaps that go nowhere** (both placements within ``MERGE_DISTANCE`` and ``MERGE_YAW``) are
  filled with stance: the foot stays down (a human shuffle the robot does not need to lift for);
- **before the first and after the last phase** the foot stands at that phase's placement, so the
  clip starts and ends with both feet down and at rest.

The result: C2 foot trajectories at any rate (smooth profiles, not per-frame solves), planted soles
that neither slide nor twist, swing feet clear of the floor. The contact labels it returns (the
extended ones) say which frames support the robot. Units: metres, radians, world frame z up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2robot.retarget.contacts import phases

#: Swing apex as a fraction of the robot's standing root height (op3: ~2 cm, G1: ~6 cm).
APEX_RATIO = 0.08
#: Share of a swing at each end in which the sole only lifts / sets down (no horizontal motion).
LIFT_LEAD = 0.25
#: m and rad: a gap whose two placements are this close is not a step (the foot stays down).
MERGE_DISTANCE = 0.005
MERGE_YAW = np.radians(3.0)


@dataclass(frozen=True)
class FootPlan:
    """targets: (T, 2, 4, 3) corner targets [left, right] in every frame the foot has a plan (NaN
    for a foot without any contact phase); contact: (T, 2) bool, the frames each sole supports
    (extended labels); swing: (T, 2) bool, planned swing frames; steps: number of swings per foot;
    apex: (n_swings,) m, the apex of each swing in order; merged: gaps filled with stance."""

    targets: np.ndarray
    contact: np.ndarray
    swing: np.ndarray
    steps: tuple[int, int]
    apex: tuple[float, ...]
    merged: int

    @property
    def pinned(self) -> np.ndarray:
        """(T, 2) bool: frames whose sole corners have a target (stance or swing)."""
        return ~np.isnan(self.targets[..., 0, 0])

    def figures(self) -> dict:
        return {"steps": list(self.steps), "swing_frames": int(self.swing.sum()),
                "apex_m": [round(a, 4) for a in self.apex], "merged_gaps": self.merged}


def minimum_jerk(s: np.ndarray) -> np.ndarray:
    """0 -> 1 over s in [0, 1] with zero speed and acceleration at both ends (clipped outside)."""
    s = np.clip(s, 0.0, 1.0)
    return s ** 3 * (10.0 - 15.0 * s + 6.0 * s * s)


def lift(s: np.ndarray) -> np.ndarray:
    """Swing height profile: 0 at s = 0 and 1 (zero speed and acceleration there), 1 at s = 0.5."""
    s = np.clip(s, 0.0, 1.0)
    return 64.0 * s ** 3 * (1.0 - s) ** 3


def _pose(corners: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """Centre (2,), yaw and corner layout (4, 2) in the sole's frame, of flat (4, 3) corners."""
    xy = corners[:, :2]
    centre = xy.mean(axis=0)
    fwd = (xy[0] + xy[1]) - (xy[2] + xy[3])
    yaw = float(np.arctan2(fwd[1], fwd[0]))
    c, s = np.cos(yaw), np.sin(yaw)
    return centre, yaw, (xy - centre) @ np.array([[c, -s], [s, c]])


def _place(centre: np.ndarray, yaw: np.ndarray, layout: np.ndarray, z: np.ndarray) -> np.ndarray:
    """(n, 4, 3) corners of soles at centres (n, 2), yaws (n,), layouts (n, 4, 2), heights (n,)."""
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    x = centre[:, None, 0] + c * layout[..., 0] - s * layout[..., 1]
    y = centre[:, None, 1] + s * layout[..., 0] + c * layout[..., 1]
    return np.stack([x, y, np.broadcast_to(z[:, None], x.shape)], axis=-1)


def swing_path(a: np.ndarray, b: np.ndarray, n: int, apex: float) -> np.ndarray:
    """(n, 4, 3) corners of the ``n`` frames strictly between placements ``a`` and ``b`` (4, 3)."""
    s = np.arange(1, n + 1) / (n + 1)
    h = minimum_jerk((s - LIFT_LEAD) / (1.0 - 2.0 * LIFT_LEAD))
    ca, ya, la = _pose(a)
    cb, yb, lb = _pose(b)
    yb = ya + (yb - ya + np.pi) % (2 * np.pi) - np.pi
    centre = ca + h[:, None] * (cb - ca)
    layout = la + h[:, None, None] * (lb - la)
    return _place(centre, ya + h * (yb - ya), layout, apex * lift(s))


def _goes_nowhere(a: np.ndarray, b: np.ndarray) -> bool:
    ca, ya, _ = _pose(a)
    cb, yb, _ = _pose(b)
    turn = abs((yb - ya + np.pi) % (2 * np.pi) - np.pi)
    return bool(np.linalg.norm(cb - ca) < MERGE_DISTANCE and turn < MERGE_YAW)


def plan_feet(anchors: np.ndarray, labels: np.ndarray, free_corners: np.ndarray, base_apex: float) -> FootPlan:
    """The plan of both soles.

    anchors: (T, 2, 4, 3) pinned corners of every contact frame (NaN elsewhere), one placement per
    phase (:func:`~.contacts.anchor_soles`, after :func:`~.anchor_gap.separate_anchors`);
    labels: (T, 2) contact frames; free_corners: (T, 2, 4, 3) corners of the unpinned solve (the
    human's foot heights); base_apex: m, the least swing apex."""
    T = labels.shape[0]
    targets = np.full(anchors.shape, np.nan)
    contact = labels.copy()
    swing = np.zeros_like(labels)
    steps, apexes, merged = [0, 0], [], 0
    runs = phases(labels)
    for f in range(labels.shape[1]):
        mine = sorted((a, b) for g, a, b in runs if g == f)
        if not mine:
            continue
        place = anchors[mine[0][0], f].copy()
        targets[:mine[0][0], f] = place                      # standing before the first phase
        contact[:mine[0][0], f] = True
        for i, (a, b) in enumerate(mine):
            if i:
                gap0, nxt = mine[i - 1][1], anchors[a, f]
                if _goes_nowhere(place, nxt):
                    targets[gap0:a, f] = place
                    contact[gap0:a, f] = True
                    merged += 1
                else:
                    height = np.nan_to_num(free_corners[gap0:a, f, :, 2], nan=0.0).min(axis=1).max(initial=0.0)
                    apex = max(base_apex, float(height))
                    targets[gap0:a, f] = swing_path(place, nxt, a - gap0, apex)
                    swing[gap0:a, f] = True
                    steps[f] += 1
                    apexes.append(apex)
                    place = nxt.copy()
            targets[a:b, f] = place
        last = mine[-1][1]
        targets[last:, f] = place                            # standing after the last phase
        contact[last:, f] = True
    return FootPlan(targets, contact, swing, (steps[0], steps[1]), tuple(apexes), merged)

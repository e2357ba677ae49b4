"""Feet that hold and lift: a target for every sole corner in every frame, from the contact schedule.

The human motion's contact schedule (per foot: phases on the floor, gaps in the air) becomes a
plan for each robot sole:

- **stance**: the four corners pinned at the phase's placement (centre and yaw where the unpinned
  solve put the sole in the phase's first frame, flat on the floor: :func:`~.contacts.anchor_soles`);
- **swing**: between two placements the sole lifts first, moves, then sets down:
  its height follows :func:`lift` (s = 0..1 over the gap: zero speed and acceleration at
  lift-off and touch-down, ``apex`` held in the middle) and its centre and yaw follow a
  minimum-jerk time warp over the middle of the gap only (``s`` in [LIFT_LEAD, 1 - LIFT_LEAD]), so no
  point of the sole moves horizontally while it is near the floor, along the path the unpinned
  solve's foot took (the human's: around the other foot), bent to leave and reach the placements. ``apex`` is the larger of
  ``APEX_RATIO`` times the robot's standing root height and the height the unpinned solve (which
  follows the human's foot) reached in that gap;
- **gaps that go nowhere** (both placements within ``MERGE_DISTANCE`` and ``MERGE_YAW``) are
  filled with stance: the foot stays down (a human shuffle the robot does not need to lift for);
- **before the first and after the last phase** the foot is left to the solver (the human's foot
  in the air at a cut: pinning it down would drag the stance foot as the body goes on).

The result: C2 foot trajectories at any rate (smooth profiles, not per-frame solves), planted soles
that neither slide nor twist, swing feet clear of the floor. The contact labels it returns (the
extended ones) say which frames support the robot. Units: metres, radians, world frame z up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2robot.retarget.anchor_gap import foot_segments, segment_distance
from motion2robot.retarget.contacts import phases, sole_yaw, yaw_rotation

#: Swing apex as a fraction of the robot's standing root height (op3: ~2 cm, G1: ~6 cm).
APEX_RATIO = 0.08
#: Share of a swing at each end in which the sole only lifts / sets down (no horizontal motion):
#: by then it is ``lift(LIFT_LEAD)`` = 0.32 of the apex up, above the check's swing clearance
#: (a quarter of the apex).
LIFT_LEAD = 0.12
#: Share of a swing at each end over which the sole rises to / descends from the apex height.
LIFT_RAMP = 0.3
#: Share of its full size a swing's sideways bend has where it is judged (see :func:`clear_swings`).
BEND_FROM = 0.2
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
    bend: float = 0.0
    too_fast: int = 0

    @property
    def pinned(self) -> np.ndarray:
        """(T, 2) bool: frames whose sole corners have a target (stance or swing)."""
        return ~np.isnan(self.targets[..., 0, 0])

    def figures(self) -> dict:
        return {"steps": list(self.steps), "swing_frames": int(self.swing.sum()),
                "apex_m": [round(a, 4) for a in self.apex], "merged_gaps": self.merged,
                "max_swing_bend_m": round(self.bend, 4), "free_swings_too_fast": self.too_fast}


def minimum_jerk(s: np.ndarray) -> np.ndarray:
    """0 -> 1 over s in [0, 1] with zero speed and acceleration at both ends (clipped outside)."""
    s = np.clip(s, 0.0, 1.0)
    return s ** 3 * (10.0 - 15.0 * s + 6.0 * s * s)


def lift(s: np.ndarray, ramp: float = LIFT_RAMP) -> np.ndarray:
    """Swing height profile over s in [0, 1]: a minimum-jerk rise over the first LIFT_RAMP, the
    apex (1) held, a minimum-jerk descent over the last LIFT_RAMP (zero speed and acceleration at
    lift-off and touch-down)."""
    s = np.clip(s, 0.0, 1.0)
    return minimum_jerk(s / ramp) * minimum_jerk((1.0 - s) / ramp)


def _pose(corners: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """Centre (2,), yaw and corner layout (4, 2) in the sole's frame, of flat (4, 3) corners."""
    centre, yaw = (v[0] for v in _centre_yaw(corners[None]))
    return centre, float(yaw), (corners[:, :2] - centre) @ yaw_rotation(float(yaw))


def _place(centre: np.ndarray, yaw: np.ndarray, layout: np.ndarray, z: np.ndarray) -> np.ndarray:
    """(n, 4, 3) corners of soles at centres (n, 2), yaws (n,), layouts (n, 4, 2), heights (n,)."""
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    x = centre[:, None, 0] + c * layout[..., 0] - s * layout[..., 1]
    y = centre[:, None, 1] + s * layout[..., 0] + c * layout[..., 1]
    return np.stack([x, y, np.broadcast_to(z[:, None], x.shape)], axis=-1)


def _centre_yaw(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centres (n, 2) and unwrapped yaws (n,) of (n, 4, 3) sole corners (NaN rows stay NaN)."""
    xy = corners[..., :2]
    yaw = sole_yaw(corners)
    ok = np.isfinite(yaw)
    if np.count_nonzero(ok) > 1:  # (one sole: nothing to unwrap)
        yaw[ok] = np.unwrap(yaw[ok])
    return xy.mean(axis=1), yaw


def straight(a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray:
    """(n + 2, 4, 3) corners moving linearly from ``a`` to ``b`` (4, 3): a ``free`` path for
    :func:`swing_path` that makes it a straight minimum-jerk swing."""
    w = np.linspace(0.0, 1.0, n + 2)[:, None, None]
    return (1.0 - w) * a + w * b


def swing_path(a: np.ndarray, b: np.ndarray, free: np.ndarray, apex: float, lead: float = LIFT_LEAD,
               ramp: float = LIFT_RAMP) -> np.ndarray:
    """(n, 4, 3) corners of the ``n`` frames strictly between placements ``a`` and ``b`` (4, 3).

    ``free``: (n + 2, 4, 3) corners of the unpinned solve from the frame of ``a`` to the frame of
    ``b``: the horizontal path follows its shape (around the other foot, as the human's foot went),
    time-warped by the lift-lead profile and bent so it leaves ``a`` and reaches ``b`` exactly.
    ``lead`` and ``ramp``: LIFT_LEAD and LIFT_RAMP unless the caller shapes its swings otherwise."""
    n = len(free) - 2
    s = np.arange(1, n + 1) / (n + 1)
    h = minimum_jerk((s - lead) / (1.0 - 2.0 * lead))
    ca, ya, la = _pose(a)
    cb, yb, lb = _pose(b)
    fc, fy = _centre_yaw(free)
    tau = h * (n + 1)                                   # warped time along the free path, in frames
    i = np.minimum(tau.astype(int), n)
    w = tau - i
    path_c = (1 - w)[:, None] * fc[i] + w[:, None] * fc[i + 1]
    path_y = (1 - w) * fy[i] + w * fy[i + 1]
    da = ca - fc[0]                                     # bend: the path's ends onto the placements
    db = cb - fc[-1]
    ya_ = fy[0] + (ya - fy[0] + np.pi) % (2 * np.pi) - np.pi
    yb_ = fy[-1] + (yb - fy[-1] + np.pi) % (2 * np.pi) - np.pi
    centre = path_c + (1 - h)[:, None] * da + h[:, None] * db
    yaw = path_y + (1 - h) * (ya_ - fy[0]) + h * (yb_ - fy[-1])
    layout = la + h[:, None, None] * (lb - la)
    return _place(centre, yaw, layout, apex * lift(s, ramp))


def clear_swings(targets: np.ndarray, swing: np.ndarray, contact: np.ndarray, local: np.ndarray,
                 radius: np.ndarray, clearance: float) -> tuple[np.ndarray, float]:
    """Swing paths bent sideways (outwards: the left foot to the stance foot's left) where they
    pass the stance foot closer than the feet's capsules allow (``local`` (2, 2, 2) sole-frame
    ends, ``radius`` (2,) m, plus ``clearance``): by ``D * 4 h (1 - h)`` over the swing (h the
    swing's horizontal progress, so the bend starts and ends with the horizontal motion, C2),
    judged where the bend is at least BEND_FROM of D (closer to the placements, they decide).
    Returns the targets and the largest bend (m)."""
    out = targets.copy()
    need = float(radius.sum() + clearance)
    worst = 0.0
    for f, a, b in phases(swing):
        g = 1 - f
        n = b - a
        s = np.arange(1, n + 1) / (n + 1)
        h = minimum_jerk((s - LIFT_LEAD) / (1.0 - 2.0 * LIFT_LEAD))
        bump = 4.0 * h * (1.0 - h)
        stance = contact[a:b, g] & ~np.isnan(out[a:b, g, 0, 0])
        if not stance.any():
            continue
        other = foot_segments(out[a:b, g], local[g])
        _, yaw_g = _centre_yaw(out[a:b, g])                  # NaN where the other foot has no target
        side = 1.0 if f == 0 else -1.0                          # left foot: towards +y of the stance sole
        lateral = side * np.stack([-np.sin(yaw_g), np.cos(yaw_g)], axis=-1)   # (n, 2)
        push = 0.0
        for _ in range(4):
            seg = foot_segments(out[a:b, f], local[f])
            gap = segment_distance(seg[:, 0], seg[:, 1], other[:, 0], other[:, 1])
            # near lift-off and touch-down the placements decide (anchor_gap keeps them apart)
            deficit = np.where(stance & (bump >= BEND_FROM), np.nan_to_num(need - gap, nan=0.0), 0.0)
            if deficit.max() <= 1e-4:
                break
            k = int(np.argmax(deficit / np.maximum(bump, BEND_FROM)))
            step = float(deficit[k] / bump[k]) + 1e-4
            out[a:b, f, :, :2] += (step * bump)[:, None, None] * lateral[k][None, None, :]
            push += step
        worst = max(worst, push)
    return out, worst


def _goes_nowhere(a: np.ndarray, b: np.ndarray) -> bool:
    ca, ya, _ = _pose(a)
    cb, yb, _ = _pose(b)
    turn = abs((yb - ya + np.pi) % (2 * np.pi) - np.pi)
    return bool(np.linalg.norm(cb - ca) < MERGE_DISTANCE and turn < MERGE_YAW)


def plan_feet(anchors: np.ndarray, labels: np.ndarray, free_corners: np.ndarray, base_apex: float,
              capsules: tuple[np.ndarray, np.ndarray] | None = None, clearance: float = 0.0,
              max_speed: float = np.inf, fps: float = 1.0, straight_swings: bool = False,
              shape: tuple[float, float] = (LIFT_LEAD, LIFT_RAMP)) -> FootPlan:
    """The plan of both soles.

    anchors: (T, 2, 4, 3) pinned corners of every contact frame (NaN elsewhere), one placement per
    phase (:func:`~.contacts.anchor_soles`, after :func:`~.anchor_gap.separate_anchors`);
    labels: (T, 2) contact frames; free_corners: (T, 2, 4, 3) corners of the unpinned solve (the
    human's foot heights); base_apex: m, the least swing apex; capsules: the feet's capsules
    (:func:`~.anchor_gap.foot_capsules`), to bend swings around the stance foot by
    :func:`clear_swings` with ``clearance`` (m); max_speed: m/s a sole corner can move at the
    clip's rate ``fps``: a swing whose plan would need more is left free (no targets: the solver
    moves the foot as the human's, within the servos' speed), since a stance foot would otherwise
    be dragged to a placement the swing could not reach in time (counted in ``too_fast``);
    straight_swings: swings go straight between the placements (:func:`straight`) instead of
    along the unpinned solve's path, and are not bent around the stance foot (for placements
    that are no longer the human's and keep the feet a stance width apart themselves); shape:
    (lead, ramp) of :func:`swing_path` and :func:`lift`."""
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
                    free = (straight(place, nxt, a - gap0) if straight_swings
                            else free_corners[gap0 - 1:a + 1, f])
                    targets[gap0:a, f] = swing_path(place, nxt, free, apex, *shape)
                    swing[gap0:a, f] = True
                    steps[f] += 1
                    apexes.append((f, gap0, apex))
                    place = nxt.copy()
            targets[a:b, f] = place
    too_fast = 0
    dropped = set()
    for f, a, b in phases(swing):
        path = targets[a - 1:b + 1, f, :, :2]
        if not np.linalg.norm(np.diff(path, axis=0), axis=-1).max() * fps <= max_speed:
            targets[a:b, f] = np.nan
            swing[a:b, f] = False
            steps[f] -= 1
            too_fast += 1
            dropped.add((f, a))
    bend = 0.0
    if capsules is not None and not straight_swings:  # re-laid placements keep the feet apart themselves
        targets, bend = clear_swings(targets, swing, contact, *capsules, clearance)
    kept = tuple(apex for f, a, apex in apexes if (f, a) not in dropped)
    return FootPlan(targets, contact, swing, (steps[0], steps[1]), kept, merged, bend, too_fast)

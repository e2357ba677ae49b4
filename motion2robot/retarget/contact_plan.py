"""The contact stage: where each sole stands, where it swings, and the support polygons.

From the free-feet solve's sole corners: each contact phase's placement
(:func:`~.contacts.anchor_soles`), pushed apart where two phases overlap in double support
(:mod:`~.anchor_gap`); then the plan of every sole in every frame (:mod:`~.footsteps`: stance
pinned, swings lifted and bent around the stance foot; without ``lift_feet``, soles pinned in
contact frames only); then the shrunk support polygon of each supported frame as half-planes
(:func:`~.constraints.support_planes`). Everything later stages pin or bound comes from here.

Units: metres; world frame z up.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from motion2robot.retarget.anchor_gap import foot_capsules, separate_anchors
from motion2robot.retarget.collision import MARGIN
from motion2robot.retarget.constraints import MARGIN_FRACTION, support_planes
from motion2robot.retarget.contacts import anchor_soles
from motion2robot.retarget.footsteps import APEX_RATIO, FootPlan, plan_feet
from motion2robot.retarget.problem import HMAX
from motion2robot.retarget.setup import Setup
from motion2robot.retarget.targets import frame_params

#: m of clearance kept between the feet's capsules (besides the collision MARGIN) when anchoring.
ANCHOR_CLEARANCE = 0.002
#: Weight of a swing sole's corner targets relative to a supporting sole's (in the solve and in the
#: projection's least squares): where the servos cannot follow a swing at this tempo, the swing
#: foot gives, not the stance foot.
SWING_WEIGHT = 0.01
#: Weight of the balance rows in frames where a planned swing is under way, relative to the
#: stance sole's rows: where a stride is too long to keep the CoM over the stance foot, the
#: balance gives (and ``check`` says so), not the stance foot (which would slide).
STEP_BALANCE_WEIGHT = 0.01
#: The fastest a planned swing may move a sole corner, as a fraction of leg length x the slowest
#: servo's speed (m/s): beyond it the swing is left to the solver (see :func:`~.footsteps.plan_feet`).
#: op3 walks (Bandai, x2.5): planned swings up to 1.2 m/s were followed within 0.1 mm; at x1 (2.5 m/s)
#: they dragged the stance foot.
FOOT_SPEED_RATIO = 1.25


@dataclass(frozen=True)
class ContactPlan:
    """labels: (T, 2) frames each sole supports; pinned: (T, 2) frames each sole's corners have a
    target; targets: (T, 2, 4, 3) those targets (NaN elsewhere); soles: the targets of the
    supporting frames only; planes: (T, HMAX, 3) shrunk support half-planes; support: (T,) frames
    with any support; margin: m the polygons are shrunk by; feet: the foot plan (None when not
    lifting); anchor_push: m, the largest push that separated overlapping placements."""

    labels: np.ndarray
    pinned: np.ndarray
    targets: np.ndarray | None
    soles: np.ndarray | None
    planes: np.ndarray
    support: np.ndarray
    margin: float
    feet: FootPlan | None
    anchor_push: float

    @property
    def weights(self) -> np.ndarray:
        """(T, 2) weight of each sole's corner targets: 1 supporting, SWING_WEIGHT swinging, 0 free."""
        return np.where(self.labels, 1.0, np.where(self.pinned, SWING_WEIGHT, 0.0))

    def params(self, setup: Setup, planes: np.ndarray | None = None, balance: bool = True) -> np.ndarray:
        """The problem's frame parameters: the scaled keypoints, every sole target, and the support
        half-planes (``planes``, default the plan's) as balance rows where ``balance`` allows."""
        on = None
        if balance and setup.opt.balance:  # a swinging foot's stance sole outranks the CoM rows
            swinging = (self.pinned & ~self.labels).any(axis=1)
            on = np.where(swinging, STEP_BALANCE_WEIGHT, 1.0) * self.support
        return frame_params(setup.problem.spec, setup.kp, self.weights, self.targets,
                            self.planes if planes is None else planes, on)


def unpinned(setup: Setup) -> ContactPlan:
    """The plan of the free-feet stage: soles asked only to touch the floor in contact frames."""
    T = len(setup.kp)
    return ContactPlan(setup.labels, setup.labels, None, None, np.tile([0.0, 0.0, 1.0], (T, HMAX, 1)),
                       setup.labels.any(axis=1), 0.0, None, 0.0)


def plan_contacts(setup: Setup, corners: np.ndarray, cap_swing_speed: bool = True,
                  place: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
                  swing_shape: tuple[float, float] | None = None) -> ContactPlan:
    """The contact plan from the free-feet solve's sole corners (T, 2, 4, 3). ``cap_swing_speed``
    off: every swing is planned, however fast; ``place``: (soles, labels) -> soles, moves the
    placements before they are separated, and the swings then go straight between them;
    ``swing_shape``: (lead, ramp) of the swings (:func:`~.footsteps.swing_path`) (all for the
    ``steps`` pattern, judged by the checks)."""
    opt, robot = setup.opt, setup.robot
    half = min(min(f.sole_half) for f in robot.config.feet)
    margin = opt.margin if opt.margin is not None else MARGIN_FRACTION * half
    if not opt.contacts:
        return replace(unpinned(setup), margin=margin)
    labels = setup.labels
    soles = anchor_soles(corners, labels)
    if place is not None:
        soles = place(soles, labels)
    feet = foot_capsules(robot)
    push = 0.0
    if feet is not None:  # phases anchored at different frames must not pin the feet into each other
        soles, push = separate_anchors(soles, labels, *feet, MARGIN + ANCHOR_CLEARANCE)
    pinned, targets, plan = labels, soles, None
    if opt.lift_feet:  # every corner of a foot with a plan has a target in every frame
        max_speed = (FOOT_SPEED_RATIO * setup.problem.spec.length * float(np.min(robot.velocity_limit))
                     if cap_swing_speed else np.inf)
        plan = plan_feet(soles, labels, corners, APEX_RATIO * float(robot.nominal_qpos[2]), feet,
                         MARGIN + ANCHOR_CLEARANCE, max_speed, setup.fps, straight_swings=place is not None,
                         **({"shape": swing_shape} if swing_shape is not None else {}))
        labels, pinned, targets = plan.contact, plan.pinned, plan.targets
        soles = np.where(labels[:, :, None, None], targets, np.nan)
    planes, support = support_planes(soles, labels, margin)
    return ContactPlan(labels, pinned, targets, soles, planes, support, margin, plan, push)

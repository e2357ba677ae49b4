"""What the caller can ask of :func:`~motion2robot.retarget.api.retarget`: one frozen dataclass."""

from __future__ import annotations

from dataclasses import dataclass, field

from motion2robot.errors import UserError
from motion2robot.retarget.costs import Weights
from motion2robot.retarget.scale import Scale
from motion2robot.retarget.tempo import DEFAULT_CAP, parse_cap, parse_tempo

#: The legs modes (what ``legs`` may be besides ``auto``, which picks one of them).
LEG_MODES = ("whole", "steps", "stance")
#: What ``legs`` may be.
LEGS = ("auto", *LEG_MODES)


@dataclass(frozen=True)
class RetargetOptions:
    """balance: keep the CoM over the shrunk support polygon (quasi-static motions; turn off for
    running/jumping). fps: resample the human motion first (None = keep its rate).
    scale: force a Scale (None = automatic, with the robot config's overrides).
    contacts: use foot contact constraints (off = free feet, only the floor; for tests).
    iterations: LM iterations of the free-feet and pinned stages; corrections: rounds of (smoothing
    within the servo's speed/acceleration + 2 Newton projections onto the hard constraints + the
    exact velocity clamp). margin: support polygon
    shrink (m; None = a quarter of the smaller sole half-extent). backend: "auto" | "lanes" | "c" | "vm" (see :mod:`~motion2robot.retarget.compiled`).
    solver: "fast" (batched LM, :mod:`~motion2robot.retarget.solver`) or "ipopt" (the per-frame
    baseline of :mod:`~motion2robot.retarget.baseline`, same costs). smoothing: round off the
    hinge trajectories to the speed/acceleration the servos can follow
    (:func:`~motion2robot.retarget.smoothing.servo_targets`) and, with balance on, the root's
    acceleration (off = only the exact velocity clamp; faster motion, may fail the torque checks).
    root_pass: finish with the exact root pass (a translation of the root only: floor, stance
    sole pinned). hold_stance_yaw: the root pass also turns the whole robot about the vertical so a
    foot alone in contact keeps its yaw (no spinning stance foot). Off by default: it stops the
    spin, but turns the body off the human's heading (walk: heading error 2 -> 11 deg, path error
    3 -> 20 cm) and its easing back makes both feet slide a little in some double-support frames
    of quasi-static clips (bandai byebye, an MDM throw), which then fail the ground check.
    dynamic_balance: with balance, a ZMP planning stage after the whole-body solve keeps the
    multi-body ZMP inside the shrunk support polygons (:mod:`~motion2robot.retarget.zmp_plan`).
    tempo: "human" | "similar" | "auto" | a slow-down factor (:mod:`~motion2robot.retarget.tempo`);
    tempo_cap: the slowest ``auto`` may go; legs: "whole" | "steps" | "stance" | "auto" (whole
    body, the walking pattern of :mod:`~motion2robot.retarget.gait`, the stance alternative of
    :mod:`~motion2robot.retarget.stance`, or the first of them that passes); with "auto" in
    either, the result is judged by ``check`` and the policy of
    :mod:`~motion2robot.retarget.executable` picks the attempt. lift_feet: every sole follows the
    plan of :mod:`~motion2robot.retarget.footsteps` (stance pinned, swings lifted clear of the floor
    and of the other foot); off = soles pinned in contact frames only, free otherwise.
    reach: a robot-shaped human motion (every keypoint reachable exactly in one pose a frame, as
    ``project`` makes) is retargeted to exactly those poses (:mod:`~motion2robot.retarget.reach`;
    off = solved like any other). replay: with tempo "auto", a slowed attempt (a pass, or the nearest to one) is replayed
    at the generated tempo (its keypoints in the human's space, retargeted again) and kept at x1.0
    when that passes, else a pass's poses are played at each faster tempo and the first that passes
    kept (:mod:`~motion2robot.retarget.replay`); off = the slowed attempt is kept."""

    balance: bool = True
    fps: float | None = None
    scale: Scale | None = None
    contacts: bool = True
    weights: Weights = field(default_factory=Weights)
    iterations: tuple[int, int] = (3, 3)
    corrections: int = 2
    margin: float | None = None
    backend: str = "auto"
    solver: str = "fast"
    smoothing: bool = True
    root_pass: bool = True
    hold_stance_yaw: bool = False
    dynamic_balance: bool = True
    tempo: str | float = "auto"
    tempo_cap: float = DEFAULT_CAP
    legs: str = "auto"
    lift_feet: bool = True
    reach: bool = True
    replay: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "tempo", parse_tempo(self.tempo))
        object.__setattr__(self, "tempo_cap", parse_cap(self.tempo_cap))
        if self.legs not in LEGS:
            raise UserError(f"--legs {self.legs!r}: choose one of {', '.join(LEGS)}")

"""Thresholds of the feasibility checks, as named fields (SI units: m, rad, s, N*m)."""

from __future__ import annotations

from dataclasses import dataclass

from motion2robot.errors import UserError

#: s, the coarsest physics step allowed (500 Hz).
MAX_TIMESTEP = 0.002


@dataclass(frozen=True)
class CheckOptions:
    """What :func:`~motion2robot.validate.check` runs and where each verdict draws the line.

    physics: run the physics playback (``rollout``).
    limit_tolerance: rad a joint may pass its range before ``joint_limits`` fails.
    velocity_margin: fraction of the servo speed limit allowed (1.0 = the datasheet figure).
    acceleration_limit: rad/s^2 for every joint; None = per joint torque_limit / armature (the
        servo's reflected rotor inertia alone caps it) or ``DEFAULT_ACCELERATION`` without armature.
    torque_margin: fraction of the torque limit allowed.
    servo_dynamics: add the MJCF's armature * qacc + damping * qvel to the inverse-dynamics torque.
    collision_depth: m of robot-robot penetration tolerated (mesh hulls graze by design).
    ground_depth: m below the floor tolerated for any geom.
    contact_height: m; a sole corner lower than this may support the robot (balance, torques).
    contact_speed: m/s; a low corner slower than this supports (or the motion's contact label).
    touch_height: m; a point of the sole lower than this touches the floor (``ground``: a point
        touching in two consecutive frames is planted and must not slip).
    slip_speed: m/s; a planted sole point moving horizontally faster than this slips or twists
        (fails ``ground``); a swing foot moving faster than this within ``swing_clearance`` of
        the floor skims it (fails ``ground``).
    swing_clearance: m a swing foot must keep above the floor while it moves; None = scaled to
        the robot (``SWING_CLEARANCE_RATIO`` times its standing root height above the soles,
        5 mm on the OP3).
    zmp_tolerance: m the ZMP may lie outside the support polygon.
    allow_flight: frames without support do not fail ``balance``.
    min_run: frames; shorter runs of violating frames in ``velocity_limits``, ``acceleration``,
        ``torque_limits``, ``balance`` and ``ground`` slipping and skimming are ignored (1 = report every frame).
    timestep: s, physics step of the playback (the servo model needs 0.002 or finer).
    fall_height_ratio: the playback falls when the torso height drops below this times its start.
    fall_tilt_deg: ... or when the torso tilts past this angle from upright.
    settle_time: s the playback holds the first frame before the motion starts.
    stream_rate: Hz, control rate of the playback's servo goals (``stream --rate``: the rollout
        sends the goals ``stream`` would send at this rate).
    sag_compensation: the playback's servo goals add the predicted servo sag (tau / kp) to the
        planned angles, as ``stream --sag-compensation`` does (:mod:`~motion2robot.validate.sag`).
    """

    physics: bool = True
    limit_tolerance: float = 1e-3
    velocity_margin: float = 1.0
    acceleration_limit: float | None = None
    torque_margin: float = 1.0
    servo_dynamics: bool = True
    collision_depth: float = 0.003
    ground_depth: float = 0.005
    contact_height: float = 0.01
    contact_speed: float = 0.3
    touch_height: float = 0.002
    slip_speed: float = 0.01
    swing_clearance: float | None = None
    zmp_tolerance: float = 0.01
    allow_flight: bool = False
    min_run: int = 1
    timestep: float = 0.002
    fall_height_ratio: float = 0.6
    fall_tilt_deg: float = 45.0
    settle_time: float = 0.5
    stream_rate: float = 100.0
    sag_compensation: bool = False

    def __post_init__(self) -> None:
        if not 0.0 < self.timestep <= MAX_TIMESTEP:
            raise UserError(f"physics timestep {self.timestep} s: the servo model needs a step in (0, {MAX_TIMESTEP}] s")
        for name in ("velocity_margin", "torque_margin", "contact_height", "touch_height", "slip_speed",
                     "fall_height_ratio", "fall_tilt_deg", "stream_rate"):
            if not getattr(self, name) > 0:
                raise UserError(f"check option {name} = {getattr(self, name)} must be positive")
        for name in ("limit_tolerance", "collision_depth", "ground_depth", "contact_speed",
                     "zmp_tolerance", "settle_time"):
            if getattr(self, name) < 0:
                raise UserError(f"check option {name} = {getattr(self, name)} must not be negative")
        if self.swing_clearance is not None and not self.swing_clearance > 0:
            raise UserError(f"check option swing_clearance = {self.swing_clearance} must be positive (or None: scaled to the robot)")
        if self.acceleration_limit is not None and not self.acceleration_limit > 0:
            raise UserError(f"check option acceleration_limit = {self.acceleration_limit} must be positive (or None)")
        if self.min_run < 1:
            raise UserError(f"check option min_run = {self.min_run} must be at least 1 frame")


#: rad/s^2, acceleration limit of joints whose model declares no armature.
DEFAULT_ACCELERATION = 100.0
#: Default swing clearance as a fraction of the robot's standing root height above its soles.
SWING_CLEARANCE_RATIO = 0.02

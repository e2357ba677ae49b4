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
    contact_height: m; a sole corner lower than this may be in contact.
    contact_speed: m/s; a low corner slower than this supports (or the motion's contact label).
    skate_speed: m/s; a low corner sliding faster than this is skating.
    zmp_tolerance: m the ZMP may lie outside the support polygon.
    allow_flight: frames without support do not fail ``balance``.
    min_run: frames; shorter runs of violating frames in ``velocity_limits``, ``acceleration``,
        ``torque_limits``, ``balance`` and ``ground`` skating are ignored (1 = report every frame).
    timestep: s, physics step of the playback (the servo model needs 0.002 or finer).
    fall_height_ratio: the playback falls when the torso height drops below this times its start.
    fall_tilt_deg: ... or when the torso tilts past this angle from upright.
    settle_time: s the playback holds the first frame before the motion starts.
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
    skate_speed: float = 0.15
    zmp_tolerance: float = 0.01
    allow_flight: bool = False
    min_run: int = 1
    timestep: float = 0.002
    fall_height_ratio: float = 0.6
    fall_tilt_deg: float = 45.0
    settle_time: float = 0.5

    def __post_init__(self) -> None:
        if not 0.0 < self.timestep <= MAX_TIMESTEP:
            raise UserError(f"physics timestep {self.timestep} s: the servo model needs a step in (0, {MAX_TIMESTEP}] s")
        for name in ("velocity_margin", "torque_margin", "contact_height", "fall_height_ratio", "fall_tilt_deg"):
            if not getattr(self, name) > 0:
                raise UserError(f"check option {name} = {getattr(self, name)} must be positive")
        for name in ("limit_tolerance", "collision_depth", "ground_depth", "contact_speed", "skate_speed",
                     "zmp_tolerance", "settle_time"):
            if getattr(self, name) < 0:
                raise UserError(f"check option {name} = {getattr(self, name)} must not be negative")
        if self.acceleration_limit is not None and not self.acceleration_limit > 0:
            raise UserError(f"check option acceleration_limit = {self.acceleration_limit} must be positive (or None)")
        if self.min_run < 1:
            raise UserError(f"check option min_run = {self.min_run} must be at least 1 frame")


#: rad/s^2, acceleration limit of joints whose model declares no armature.
DEFAULT_ACCELERATION = 100.0

"""THE one place naming every term of the retargeting problem and its weight.

Cost = sum over terms of ``weight * ||residual||^2``. Position residuals are divided by the
robot's leg length (so the weights do not depend on the robot's size); direction and axis
residuals are differences of unit vectors; joint residuals are radians. Hard constraints
(contact, floor, balance, self-collision) are stiff penalty terms here and are finished by the
exact passes in :mod:`motion2robot.retarget.constraints`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

#: Terms evaluated by the compiled per-frame function, in the order of its weight vector.
FRAME_TERMS: tuple[str, ...] = (
    "keypoint",        # keypoint positions vs the scaled human keypoints
    "direction",       # limb directions (hip->knee, elbow->wrist, ...) vs the human's
    "pelvis_heading",  # root body's left axis vs the human pelvis left axis (hips line)
    "torso_up",        # torso body's up axis vs the human spine direction
    "foot_heading",    # each foot's forward axis vs the human ankle->toe direction (horizontal)
    "sole_flat",       # each sole's normal vs world up
    "posture",         # hinge angles vs the nominal posture
    "contact_z",       # sole corners on the floor (z = target) in contact frames
    "contact_xy",      # sole corners at their anchored xy in contact frames (no sliding, no twisting)
    "floor",           # no sole corner below z = 0 (hinge), every frame
    "balance",         # CoM ground projection inside the shrunk support polygon (hinge)
    "self_collision",  # limb capsules vs torso / other leg: distance >= sum of radii (hinge);
                       # bodies <= 2 hinges apart: joint-space cuts (joint_cuts.py), linear
)

#: The terms that are hard constraints (residual zero when satisfied), corrected exactly at the end.
HARD_TERMS: tuple[str, ...] = ("contact_z", "contact_xy", "floor", "balance", "self_collision")


@dataclass(frozen=True)
class Weights:
    """Weights of every cost term (dimensionless; see the module docstring for the units)."""

    keypoint: float = 1.0
    direction: float = 0.3
    pelvis_heading: float = 0.1
    torso_up: float = 0.05
    foot_heading: float = 0.05
    sole_flat: float = 0.05
    posture: float = 2e-3
    contact_z: float = 1e5
    contact_xy: float = 1e5
    floor: float = 1e5
    balance: float = 1e5
    self_collision: float = 1e6
    # temporal terms, applied between neighbouring frames by the solver (per-frame units: rad, m)
    velocity: float = 2e-3
    # 20x the first tuning: at 5e-3 the LM's few iterations left single-frame second differences
    # of 0.2 rad (100 rad/s^2 at 20 fps, the servo's whole torque on its rotor) in the legs of an
    # MDM throw; 0.1 removes them and tracks as closely (keypoint error 50.8 -> 44 mm)
    acceleration: float = 0.1
    # Levenberg-Marquardt damping added to the Gauss-Newton normal matrix
    damping: float = 1e-6

    def frame_vector(self) -> list[float]:
        """Weights of :data:`FRAME_TERMS` in order (the compiled function's ``w`` input)."""
        return [float(getattr(self, t)) for t in FRAME_TERMS]

    def as_dict(self) -> dict[str, float]:
        return asdict(self)

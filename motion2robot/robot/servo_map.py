"""The servo map of a robot: which Dynamixel drives which joint, and how angles become ticks.

TOML (section ``[servos]`` of a robot config)::

    [servos]
    model = "XM430-W350"        # control table / datasheet name
    baud = 2000000              # bus baud rate the robot's servos are set to
    ticks_per_rev = 4096
    center = 2048               # ticks at 0 rad (before the per-joint offset)
    [servos.ids]                # joint -> Dynamixel ID
    r_sho_pitch = 1
    [servos.sign]               # optional, joint -> +1 | -1 (default +1)
    [servos.offset]             # optional, joint -> zero offset in ticks (default 0); a
                                # calibration file overrides these

ticks = center + offset + sign * angle * ticks_per_rev / (2 pi)
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ServoSpec:
    """One servo: the joint it drives, its bus ID, direction sign and zero offset (ticks)."""

    joint: str
    id: int
    sign: int = 1
    offset: int = 0


@dataclass(frozen=True)
class ServoMap:
    """All servos of a robot, in the robot's hinge order (joints without a servo are absent)."""

    model: str
    baud: int
    ticks_per_rev: int
    center: int
    servos: tuple[ServoSpec, ...]

    def by_joint(self) -> dict[str, ServoSpec]:
        return {s.joint: s for s in self.servos}

    def by_id(self) -> dict[int, ServoSpec]:
        return {s.id: s for s in self.servos}

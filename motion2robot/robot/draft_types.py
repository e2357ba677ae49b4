"""The drafted robot config as data (see :mod:`motion2robot.robot.draft`); units: m, rad, N*m, rad/s."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class JointDraft:
    name: str
    range: tuple[float, float] | None  # None: the model's
    torque: float
    kp: float
    note: str = ""  # comment for the TOML; starts with CHECK when a human should look


@dataclass(frozen=True)
class KeypointDraft:
    human: str
    body: str
    offset: tuple[float, float, float]
    weight: float = 1.0
    note: str = ""


@dataclass(frozen=True)
class FootDraft:
    side: str
    body: str
    sole_center: tuple[float, float, float]
    sole_half: tuple[float, float]
    note: str = ""
    sole_quat: tuple[float, float, float, float] | None = None  # sole frame in the body frame; None: the body's


@dataclass(frozen=True)
class Draft:
    """A drafted robot config: :func:`motion2robot.robot.draft_toml.render` gives its TOML; ``guesses`` says what was
    inferred, ``checks`` what needs a human look; ``height`` is the loaded draft's nominal height (m)."""

    name: str
    model_ref: str
    mjcf: Path
    menagerie: str | None
    entry: str | None
    root_body: str
    torso_body: str
    default_velocity: float
    default_torque: float
    default_kp: float
    joints: tuple[JointDraft, ...]
    nominal: dict
    keypoints: tuple[KeypointDraft, ...]
    feet: tuple[FootDraft, FootDraft]
    guesses: tuple[str, ...]
    checks: tuple[str, ...]
    height: float = float("nan")

    @property
    def n_joints(self) -> int:
        return len(self.joints)



def rounded(v, nd: int = 4) -> tuple[float, ...]:
    """``v`` as a tuple of floats rounded to ``nd`` decimals (no negative zeros), for writing."""
    return tuple(round(float(x), nd) + 0.0 for x in v)

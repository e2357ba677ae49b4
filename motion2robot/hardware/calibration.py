"""Joint radians <-> servo ticks through the servo map, and calibration files of zero offsets.

ticks = center + offset + sign * angle * ticks_per_rev / (2 pi), rounded to the nearest tick;
ticks -> radians -> ticks is exact, radians -> ticks -> radians is within half a tick.
A calibration file (JSON) holds per-joint zero offsets recorded by
``motion2robot servos calibrate`` and overrides the servo map's offsets.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motion2robot.errors import InputFileError, RobotConfigError
from motion2robot.robot.servo_map import ServoMap

CALIBRATION_FORMAT = "motion2robot-calibration/1"


@dataclass(frozen=True, eq=False)
class Calibration:
    """Arrays over the servo map's joints (its order): IDs, signs, offsets (ticks)."""

    joints: tuple[str, ...]
    ids: np.ndarray
    sign: np.ndarray
    offset: np.ndarray
    center: int
    ticks_per_rev: int

    @classmethod
    def from_servo_map(cls, servo_map: ServoMap, offsets: Mapping[str, int] | None = None) -> Calibration:
        offsets = dict(offsets or {})
        unknown = sorted(set(offsets) - {s.joint for s in servo_map.servos})
        if unknown:
            raise RobotConfigError(f"calibration names joints {', '.join(unknown)} that have no servo; "
                                   "record it again with 'motion2robot servos calibrate'")
        for s in servo_map.servos:
            if s.sign not in (1, -1):
                raise RobotConfigError(f"servo map: sign of {s.joint} must be +1 or -1, got {s.sign}")
        ids = [s.id for s in servo_map.servos]
        if len(set(ids)) != len(ids):
            raise RobotConfigError("servo map: duplicate servo IDs; give each joint its own ID")
        return cls(
            tuple(s.joint for s in servo_map.servos),
            np.array(ids, dtype=np.int64),
            np.array([s.sign for s in servo_map.servos], dtype=np.int64),
            np.array([int(offsets.get(s.joint, s.offset)) for s in servo_map.servos], dtype=np.int64),
            int(servo_map.center), int(servo_map.ticks_per_rev))

    @property
    def ticks_per_rad(self) -> float:
        return self.ticks_per_rev / (2.0 * math.pi)

    def ticks_float(self, q: np.ndarray) -> np.ndarray:
        """Unrounded ticks of joint angles ``q`` (rad, (..., n)); NaN stays NaN."""
        return self.center + self.offset + self.sign * np.asarray(q, dtype=np.float64) * self.ticks_per_rad

    def to_ticks(self, q: np.ndarray) -> np.ndarray:
        """Nearest integer ticks of finite joint angles ``q`` (rad)."""
        t = self.ticks_float(q)
        if not np.all(np.isfinite(t)):
            raise ValueError("to_ticks: angles must be finite")
        return np.rint(t).astype(np.int64)

    def to_radians(self, ticks: np.ndarray) -> np.ndarray:
        """Joint angles (rad) of servo ticks ((..., n) integers)."""
        return self.sign * (np.asarray(ticks, dtype=np.float64) - self.center - self.offset) / self.ticks_per_rad


def record_zero_offsets(servo_map: ServoMap, present: Mapping[int, int],
                        nominal: Mapping[str, float]) -> dict[str, int]:
    """Offsets (ticks) that make ``present`` ticks (by servo ID) read as the ``nominal`` angles
    (rad, by joint; 0 when absent), i.e. offset = present - center - sign * nominal * k."""
    k = servo_map.ticks_per_rev / (2.0 * math.pi)
    out = {}
    for s in servo_map.servos:
        if s.id not in present:
            raise RobotConfigError(f"calibration: no present position for servo {s.id} ({s.joint})")
        out[s.joint] = round(present[s.id] - servo_map.center - s.sign * float(nominal.get(s.joint, 0.0)) * k)
    return out


def save_calibration(path: str | Path, robot: str, offsets: Mapping[str, int]) -> Path:
    """Write a calibration file (JSON, atomically)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    doc = {"format": CALIBRATION_FORMAT, "robot": robot,
           "recorded": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "offsets": {j: int(v) for j, v in offsets.items()}}
    tmp = path.with_name(path.name + ".part")
    tmp.write_text(json.dumps(doc, indent=1) + "\n")
    tmp.replace(path)
    return path


def load_calibration(path: str | Path) -> dict[str, int]:
    """Zero offsets (ticks, by joint) from a calibration file."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as err:
        raise InputFileError(f"{path}: cannot read the calibration ({err}); record it with "
                             "'motion2robot servos calibrate'") from err
    if not isinstance(doc, dict) or doc.get("format") != CALIBRATION_FORMAT or not isinstance(doc.get("offsets"), dict):
        raise InputFileError(f"{path}: not a motion2robot calibration file; record it with 'motion2robot servos calibrate'")
    try:
        return {str(j): int(v) for j, v in doc["offsets"].items()}
    except (TypeError, ValueError) as err:
        raise InputFileError(f"{path}: offsets must be integers (ticks) ({err})") from err

"""The :class:`FeasibilityReport`: per-check verdicts and figures, reasons, per-frame evidence."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from motion2robot.util.jsonable import plain

#: Checks in report order; ``trajectory`` is a figure and never decides the verdict.
CHECK_NAMES = ("joint_limits", "velocity_limits", "acceleration", "torque_limits", "self_collision",
               "ground", "balance", "rollout", "trajectory")
VERDICT_CHECKS = CHECK_NAMES[:-1]


@dataclass(frozen=True, eq=False)
class FeasibilityReport:
    """feasible: every verdict check that ran is ok. checks: name -> {"ok": bool, figures...,
    "frames": [int]} (a check that did not run has "skipped": why). reasons: sentences.
    figures: summary numbers. series: per-frame arrays for plots (not in JSON), see the
    contracts: q, qvel, torque_ratio, com_xy, zmp_xy, support_margin, foot_height, contacts,
    and rollout_q, rollout_time, torso_height (and rollout_qpos, the full simulated state) when
    the playback ran."""

    feasible: bool
    checks: dict[str, dict]
    reasons: list[str]
    figures: dict[str, Any]
    robot: str
    fps: float
    frames: int
    series: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def failed(self) -> list[str]:
        return [n for n in VERDICT_CHECKS if n in self.checks and not self.checks[n].get("skipped")
                and not self.checks[n]["ok"]]

    def to_dict(self) -> dict:
        """JSON-serialisable content (no series)."""
        return plain({"feasible": self.feasible, "checks": self.checks, "reasons": self.reasons,
                       "figures": self.figures, "robot": self.robot, "fps": self.fps, "frames": self.frames})

    def to_json(self, path: str | Path) -> Path:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.to_dict(), indent=1) + "\n")
        return path


def verdict(checks: dict[str, dict]) -> bool:
    """True when every verdict check present and not skipped is ok."""
    return all(c["ok"] for n, c in checks.items() if n in VERDICT_CHECKS and not c.get("skipped"))



"""What the tempo/legs policy's judge already knows about an attempt, so no check runs twice.

The policy judges attempts with ``check(..., physics_if_feasible=True)``: the physics playback runs
only when every kinematic check passes. The report it returns for an attempt that played back is
therefore the full report (the same checks, the same playback); only an attempt whose playback was
skipped because a kinematic check failed needs a second, full check when it is the one returned.
"""

from __future__ import annotations


def needs_full_check(report: object, check_options: object | None) -> bool:
    """True when ``report`` (a FeasibilityReport made with ``physics_if_feasible``) lacks the
    physics playback that a full check with ``check_options`` would run: playback asked for, two
    frames or more, and the rollout skipped (a kinematic check failed first)."""
    if check_options is not None and not getattr(check_options, "physics", True):
        return False
    if getattr(report, "frames", 0) < 2:
        return False
    return "skipped" in report.checks.get("rollout", {})

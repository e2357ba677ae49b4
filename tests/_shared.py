"""Where the shared test data lives (../shared beside the repo, or $MOTION2ROBOT_SHARED).

Tests that need real clips or menagerie models use ``requires_shared`` and skip cleanly when the
folder is absent, so the package still tests on a user's machine.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest


def _find_shared() -> Path | None:
    env = os.environ.get("MOTION2ROBOT_SHARED")
    candidates = [Path(env)] if env else []
    candidates.append(Path(__file__).resolve().parents[2] / "shared")
    for c in candidates:
        if (c / "motions").is_dir():
            return c
    return None


SHARED: Path | None = _find_shared()
MOTIONS: Path | None = SHARED / "motions" if SHARED else None
MENAGERIE: Path | None = (
    Path(os.environ["MENAGERIE_ROOT"]) if os.environ.get("MENAGERIE_ROOT")
    else (SHARED / "menagerie" if SHARED and (SHARED / "menagerie").is_dir() else None)
)

requires_shared = pytest.mark.skipif(SHARED is None, reason="../shared (real motion clips) is absent")
requires_menagerie = pytest.mark.skipif(
    MENAGERIE is None or not MENAGERIE.is_dir(), reason="no menagerie root (set MENAGERIE_ROOT)"
)


def load_menagerie(name: str):
    """``load_robot(name)`` for a ``menagerie:`` robot with MENAGERIE_ROOT pointing at the shared
    menagerie for the load only."""
    from unittest import mock

    from motion2robot.robot import load_robot

    with mock.patch.dict(os.environ, {"MENAGERIE_ROOT": str(MENAGERIE)}):
        return load_robot(name)

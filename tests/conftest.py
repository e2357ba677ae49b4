"""Fixtures shared by the test modules."""

from __future__ import annotations

import pytest

from tests._shared import MENAGERIE


@pytest.fixture
def menagerie_env(monkeypatch):
    """MENAGERIE_ROOT pointed at the shared menagerie (when there is one) for one test, with the
    robot cache cleared before and after, so no robot loaded under it outlives the test."""
    from motion2robot.robot import load_robot

    if MENAGERIE is not None:
        monkeypatch.setenv("MENAGERIE_ROOT", str(MENAGERIE))
    load_robot.cache_clear()
    yield
    load_robot.cache_clear()

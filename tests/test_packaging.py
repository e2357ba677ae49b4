"""The wheel ships the robots (robots/ -> motion2robot.robots) and worlds (sim/ -> motion2robot.worlds)."""

import importlib.util
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.skipif(importlib.util.find_spec("wheel") is None, reason="needs the 'wheel' package (test extra)")
def test_wheel_contains_robot_and_world_data(tmp_path):
    r = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", str(ROOT), "--no-deps", "--no-build-isolation", "-q", "-w", str(tmp_path)],
        capture_output=True, text=True, cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr[-2000:]
    (whl,) = tmp_path.glob("motion2robot-*.whl")
    names = set(zipfile.ZipFile(whl).namelist())
    for expected in (
        "motion2robot/robots/op3/op3.xml",
        "motion2robot/robots/op3/op3.toml",
        "motion2robot/robots/menagerie/unitree_g1.toml",
        "motion2robot/robots/menagerie/unitree_h1.toml",
        "motion2robot/worlds/flat.xml",
        "motion2robot/data/demo_wave_squat.npy",
        "motion2robot/cli/__init__.py",
    ):
        assert expected in names, f"{expected} missing from the wheel"
    assert not any(n.startswith(("tests/", "scripts/")) for n in names)

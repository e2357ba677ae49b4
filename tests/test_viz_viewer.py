"""The interactive viewer: a smoke test under a virtual X display (skipped without xvfb-run)."""

from __future__ import annotations

import os
import signal
import shutil
import subprocess
import sys

import pytest

SCRIPT = """
import numpy as np
from motion2robot.robot import load_robot
from motion2robot.robot.world import make_world
from motion2robot.robot_motion import RobotMotion
from motion2robot.viz.scene import make_playable
from motion2robot.viz.viewer import play_in_viewer

r = load_robot("op3")
q = np.tile(r.nominal_qpos, (40, 1))
q[:, 7 + r.joint_index("l_sho_pitch")] = np.linspace(0, 1, 40)
m = RobotMotion(q, 20.0, r.joint_names, r.name, {})

class Rep:
    checks = {"balance": {"ok": False, "frames": [5, 6]}}

pb = play_in_viewer(make_world(r), make_playable(m, r, report=Rep()), stop_after=1.0)
print("PLAYED", pb.frame, pb.failing, flush=True)
import os
os._exit(0)  # skip interpreter teardown: the viewer's GLFW thread can hang it under Xvfb
"""


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run is not installed (apt-get install xvfb)")
def test_viewer_plays_under_a_virtual_display():
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL")}
    proc = subprocess.Popen(["xvfb-run", "-a", "-s", "-screen 0 800x600x24", sys.executable, "-c", SCRIPT],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True)
    try:
        stdout, stderr = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)  # xvfb-run, its Xvfb and python: this test's own group
        stdout, stderr = proc.communicate()
    line = next((ln for ln in stdout.splitlines() if ln.startswith("PLAYED")), None)
    assert line is not None, stderr[-2000:]
    frame = int(line.split()[1])
    assert frame > 0  # real-time playback advanced while the window was open
    assert "[5, 6]" in line

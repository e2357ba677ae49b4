"""`motion2robot demo`: the whole pipeline on the bundled motion and robot, with its outputs kept."""

import json

import numpy as np

from motion2robot.cli import main
from motion2robot.hardware.telemetry import read_telemetry
from motion2robot.robot_motion import RobotMotion


def test_demo_runs_the_whole_pipeline(tmp_path, capsys):
    code = main(["demo", "-o", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0, out
    for section in ("1. retarget", "2. check in MuJoCo", "3. stream at 100 Hz"):
        assert section in out
    assert "torque off on all servos" in out and "overruns" in out
    motion = RobotMotion.load(tmp_path / "demo_op3.npz")
    assert motion.num_frames == 120 and len(motion.joint_names) == 20
    report = json.loads((tmp_path / "report.json").read_text())
    assert set(report["checks"]) >= {"joint_limits", "velocity_limits", "torque_limits", "self_collision",
                                     "ground", "balance", "rollout"}
    assert report["checks"]["joint_limits"]["ok"] is True  # the retargeter's hard limits hold
    assert (tmp_path / "report.html").stat().st_size > 10_000
    tel = read_telemetry(tmp_path / "stream.telemetry.jsonl")
    assert len(tel.ticks) >= 600 and tel.stop is not None and not tel.truncated  # 6 s at 100 Hz + ramps
    cmd = np.array([t["cmd"] for t in tel.ticks])
    assert cmd.shape[1] == 20 and np.all(np.isfinite(cmd))

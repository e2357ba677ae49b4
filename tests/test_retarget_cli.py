"""The retarget/demo commands, bad input, and the bundled demo motion."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.errors import RobotConfigError, SolverError
from motion2robot.motion import HumanMotion
from motion2robot.retarget import retarget
from motion2robot.robot import load_robot
from tests._shared import MOTIONS, requires_shared

ROOT = Path(__file__).resolve().parents[1]
OP3_XML = ROOT / "robots" / "op3" / "op3.xml"


@requires_shared
def test_cli_writes_npz_with_exactly_five_keys(tmp_path, capsys):
    out = tmp_path / "arm.npz"
    assert main(["retarget", str(MOTIONS / "humanml3d_joints" / "M010968.npy"), "-o", str(out)]) == 0
    with np.load(out, allow_pickle=False) as z:
        assert sorted(z.files) == sorted(["qpos", "fps", "joint_names", "robot", "meta"])
        assert z["qpos"].shape == (70, 27)
        meta = json.loads(str(z["meta"]))
    assert meta["source"].endswith("M010968.npy") and "solver" in meta and "scale" in meta
    assert "70 frames" in capsys.readouterr().out


@requires_shared
def test_cli_fps_resamples(tmp_path):
    out = tmp_path / "arm40.npz"
    assert main(["retarget", str(MOTIONS / "humanml3d_joints" / "M010968.npy"), "--fps", "40", "-o", str(out)]) == 0
    with np.load(out, allow_pickle=False) as z:
        assert float(z["fps"]) == 40.0 and 135 <= z["qpos"].shape[0] <= 141


@requires_shared
def test_cli_clip_all_writes_one_file_per_clip(tmp_path):
    out = tmp_path / "mdm.npz"
    src = MOTIONS / "mdm_results" / "mdm_walk_pickup_results.npy"
    assert main(["retarget", str(src), "--clip", "all", "--no-balance", "--tempo", "human", "--legs", "whole",
                 "-o", str(out)]) == 0
    assert sorted(p.name for p in tmp_path.glob("*.npz")) == ["mdm_clip0.npz", "mdm_clip1.npz", "mdm_clip2.npz"]


@requires_shared
def test_cli_multi_clip_without_clip_is_a_clear_error(tmp_path, capsys):
    src = MOTIONS / "mdm_results" / "mdm_walk_pickup_results.npy"
    assert main(["retarget", str(src), "-o", str(tmp_path / "x.npz")]) == 2
    err = capsys.readouterr().err
    assert "--clip" in err and len(err.strip().splitlines()) == 1


def test_demo_runs_and_reports(capsys):
    assert main(["demo"]) == 0
    out = capsys.readouterr().out
    assert "120 frames" in out and "0 violations" in out and "frames/s" in out


def test_shipped_demo_motion_is_what_the_script_makes():
    spec = importlib.util.spec_from_file_location("make_demo_motion", ROOT / "scripts" / "make_demo_motion.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    shipped = np.load(ROOT / "motion2robot" / "data" / "demo_wave_squat.npy")
    assert shipped.dtype == np.float32 and shipped.shape == (120, 22, 3)
    assert np.array_equal(shipped, mod.make_demo_motion())


def _standing(T: int) -> np.ndarray:
    from motion2robot.cli.cmd_demo import demo_motion_path
    from motion2robot.motion import read_motion

    return read_motion(demo_motion_path())[0].positions[:T]


def test_feet_never_touching_is_an_error():
    pos = _standing(20) + np.array([0.0, 0.0, 0.5])
    human = HumanMotion(pos, 20.0, contacts=np.zeros((20, 2), bool), meta={"source": "floating.npy"})
    with pytest.raises(SolverError, match="never touch"):
        retarget(human, load_robot("op3"))


def test_single_frame_is_an_error():
    human = HumanMotion(_standing(1), 20.0, meta={"source": "one.npy"})
    with pytest.raises(SolverError, match="1 frame"):
        retarget(human, load_robot("op3"))


def _toml(tmp_path: Path, feet: bool, body: str = "l_knee_link") -> Path:
    text = f'''name = "broken"
[model]
mjcf = "{OP3_XML}"
root_body = "body_link"
[keypoints]
pelvis = "body_link"
left_knee = "{body}"
'''
    for side in ("left", "right") if feet else ():
        text += f'''[feet.{side}]
body = "{'l' if side == 'left' else 'r'}_ank_roll_link"
sole_center = [0.024, 0.0, -0.0305]
sole_half = [0.06, 0.03]
'''
    path = tmp_path / "broken.toml"
    path.write_text(text)
    return path


def test_robot_without_feet_is_an_error(tmp_path):
    with pytest.raises(RobotConfigError, match="feet"):
        load_robot(str(_toml(tmp_path, feet=False)))


def test_keypoint_on_a_missing_body_is_an_error(tmp_path):
    with pytest.raises(RobotConfigError, match="no_such_link"):
        load_robot(str(_toml(tmp_path, feet=True, body="no_such_link")))


def test_cli_iterations_buys_accuracy(tmp_path):
    demo = ROOT / "motion2robot" / "data" / "demo_wave_squat.npy"
    error = {}
    for its in ("3,3", "6"):
        out = tmp_path / f"demo_{its}.npz"
        assert main(["retarget", str(demo), "--iterations", its, "-o", str(out)]) == 0
        with np.load(out, allow_pickle=False) as z:
            solver_meta = json.loads(str(z["meta"]))["solver"]
        assert max(solver_meta["iterations"]) <= int(its[-1])
        error[its] = np.mean(solver_meta["residual_per_frame"])
    assert error["6"] < error["3,3"]


@pytest.mark.parametrize("bad", ["0", "3,x", "1,2,3"])
def test_cli_bad_iterations_is_a_usage_error(bad, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["retarget", "x.npy", "--iterations", bad])
    assert exc.value.code == 2 and "--iterations" in capsys.readouterr().err


def test_an_output_that_cannot_be_written_is_refused_before_the_work(tmp_path, capsys):
    """Issue 20: '-o' pointing at a directory was found after the solve (exit 3, a .part file left
    behind). A clip whose feet never touch the floor would fail the solve: the -o error comes first."""
    from tests.test_motion_support import walking_yup

    np.save(tmp_path / "m.npy", walking_yup(30))
    (tmp_path / "outdir").mkdir()
    (tmp_path / "afile").write_text("x")
    for out, words in ((tmp_path / "outdir", f"{tmp_path / 'outdir'}: is a directory; give a file name for the "
                                             f"robot motion, e.g. {tmp_path / 'outdir' / 'out.npz'}"),
                       (tmp_path / "afile" / "o.npz", "cannot create its folder for the robot motion")):
        assert main(["retarget", str(tmp_path / "m.npy"), "-o", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("motion2robot: error: ") and words in err[0], err
    assert not list(tmp_path.rglob("*.part*")) and not any((tmp_path / "outdir").iterdir())

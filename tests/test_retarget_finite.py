"""Nothing non-finite is ever written (issue 20: one value of 3e38 in a HumanML3D file made
'retarget' write an all-NaN motion and exit 0)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.errors import SolverError
from motion2robot.motion.human import HumanMotion
from motion2robot.retarget.finite import check_solution
from tests.test_motion_support import walking_yup


def test_cli_refuses_3e38_naming_frame_and_joint(tmp_path, capsys):
    j = walking_yup(30)
    j[7, 20, 1] = 3e38  # left wrist, frame 7
    np.save(tmp_path / "m.npy", j)
    out = tmp_path / "o.npz"
    code = main(["retarget", str(tmp_path / "m.npy"), "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("motion2robot: error: ")
    assert "frame 7" in err[0] and "left_wrist" in err[0]
    assert not out.exists() and not list(tmp_path.glob("*.part*"))


def test_api_refuses_extreme_keypoints_before_the_solve():
    from motion2robot.retarget import retarget
    from motion2robot.robot import load_robot

    pos = np.zeros((20, 22, 3)) + np.linspace(0, 1.6, 22)[None, :, None] * [0, 0, 1]
    pos[11, 15] = [0.0, 0.0, 1e30]  # past every reader check: handed over in-process
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # and no RuntimeWarning on the way
        with pytest.raises(SolverError, match="frame 11, keypoint head"):
            retarget(HumanMotion(pos, 20.0, meta={"source": "api"}), load_robot("op3"))


def test_a_non_finite_solution_is_named_not_written():
    q = np.zeros((5, 27))
    q[3, 9] = np.inf
    with pytest.raises(SolverError, match="frame 3, joint j2"):
        check_solution(q, [f"j{i}" for i in range(20)], "clip")

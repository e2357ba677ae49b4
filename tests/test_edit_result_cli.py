"""``edit RESULT.npy``: one editor result file holding the edit and its source, through a body model."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2robot.cli import main
from tests.test_motion_body_model import _motion, _quat_matrix, smplh_fixture


def test_editor_result_file_is_a_pair(tmp_path: Path, capsys) -> None:
    model = smplh_fixture(tmp_path / "model.npz")
    aa, trans = _motion(60)
    aa[:, 1:] *= 0.3  # a calm pose
    edited = aa.copy()
    edited[20:40, 17] += [0.0, 0.0, 1.0]  # the right shoulder turns in frames 20-39
    to135 = lambda a: np.concatenate([trans, _quat_matrix(a)[:, :, :2, :].reshape(len(a), 132)], axis=1)
    res = {"pose": to135(edited), "pose_source": to135(aa), "pose_target": to135(edited), "text": "raise the right arm"}
    np.save(tmp_path / "0007.npy", np.array(res, dtype=object), allow_pickle=True)
    code = main(["edit", str(tmp_path / "0007.npy"), "--body-model", str(model), "--no-physics"])
    out = capsys.readouterr().out
    assert code in (0, 1)
    assert "human edit: right_arm changed in frames" in out and "left_arm" not in out
    assert (tmp_path / "0007_edited_op3.npz").is_file()

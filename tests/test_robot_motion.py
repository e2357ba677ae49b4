"""RobotMotion: the .npz contract (exact keys, no pickle) and clear errors on bad files."""

import json
import zipfile

import numpy as np
import pytest

from motion2robot.errors import InputFileError
from motion2robot.robot_motion import NPZ_KEYS, RobotMotion


def _motion(T=5, n=3):
    q = np.zeros((T, 7 + n))
    q[:, 3] = 1.0
    q[:, 7:] = np.linspace(0, 1, T)[:, None]
    return RobotMotion(q, 20.0, ("a", "b", "c"), "op3", {"source": "x.npy", "scale": {"legs": 0.3}})


def test_roundtrip_has_exactly_the_contract_keys(tmp_path):
    m = _motion()
    p = m.save(tmp_path / "m.npz")
    with zipfile.ZipFile(p) as z:
        assert sorted(n[:-4] for n in z.namelist()) == sorted(NPZ_KEYS)
    with np.load(p, allow_pickle=False) as z:  # loads without pickle
        assert json.loads(str(z["meta"]))["scale"] == {"legs": 0.3}
    back = RobotMotion.load(p)
    np.testing.assert_array_equal(back.qpos, m.qpos)
    assert back.joint_names == ("a", "b", "c") and back.robot == "op3" and back.fps == 20.0
    assert back.meta["source"] == "x.npy"


def test_shape_mismatch_rejected():
    with pytest.raises(ValueError):
        RobotMotion(np.zeros((4, 9)), 20, ("a", "b", "c"), "op3")


@pytest.mark.parametrize("case", ["dir", "missing", "notzip", "nokeys", "nan"])
def test_bad_files_give_one_line_errors(tmp_path, case):
    p = tmp_path / "bad.npz"
    if case == "dir":
        p.mkdir()
    elif case == "notzip":
        p.write_bytes(b"hello")
    elif case == "nokeys":
        np.savez(p, x=np.zeros(3))
    elif case == "nan":
        m = _motion()
        q = m.qpos.copy()
        q[2, 8] = np.nan
        with pytest.raises(ValueError, match="refusing to write"):  # the writer never writes NaN (issue 20)
            RobotMotion(q, 20.0, m.joint_names, "op3").save(p)
        assert not p.exists() and not list(tmp_path.glob("*.part*"))
        np.savez(p, qpos=q, fps=np.float64(20.0), joint_names=np.array(m.joint_names), robot=np.array("op3"),
                 meta=np.array("{}"))
    with pytest.raises(InputFileError) as e:
        RobotMotion.load(p)
    msg = str(e.value)
    assert "\n" not in msg and str(p) in msg
    if case == "nan":
        assert "frames 2" in msg

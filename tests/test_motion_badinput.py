"""Bad input: one line on stderr and exit code 2 from ``motion2robot inspect``; the pickle guard."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.errors import InputFileError
from motion2robot.motion import read_motion
from tests.test_motion_support import bvh_text, walking_yup


def _err(capsys, *argv: str) -> str:
    code = main(["inspect", *map(str, argv)])
    out = capsys.readouterr()
    lines = out.err.strip().splitlines()
    assert code == 2, out
    assert len(lines) == 1 and lines[0].startswith("motion2robot: error: "), out.err
    assert "Traceback" not in out.err
    return lines[0]


def _npy(path: Path, arr: np.ndarray) -> Path:
    np.save(path, arr)
    return path


def test_empty_file(tmp_path, capsys) -> None:
    (tmp_path / "e.npy").write_bytes(b"")
    assert "is empty" in _err(capsys, tmp_path / "e.npy")


def test_not_a_numpy_file(tmp_path, capsys) -> None:
    (tmp_path / "t.npy").write_text("hello, I am text\n")
    assert "not a numpy .npy file" in _err(capsys, tmp_path / "t.npy")


@pytest.mark.parametrize("shape", [(30, 21, 3), (30, 262)])
def test_wrong_shape(tmp_path, capsys, shape) -> None:
    msg = _err(capsys, _npy(tmp_path / "w.npy", np.zeros(shape, np.float32)))
    assert f"shape {shape}" in msg


def test_nan_frames_are_named(tmp_path, capsys) -> None:
    a = walking_yup(30)
    a[3:6, 4] = np.nan
    a[20, 0, 1] = np.inf
    msg = _err(capsys, _npy(tmp_path / "n.npy", a))
    assert "NaN/inf" in msg and "frames 3-5, 20" in msg


def test_nan_in_features_are_named(tmp_path, capsys) -> None:
    f = np.zeros((30, 263), np.float32)
    f[:, 3] = 0.9
    f[7, 10] = np.nan
    assert "frames 7" in _err(capsys, _npy(tmp_path / "f.npy", f))


def test_fewer_than_two_frames(tmp_path, capsys) -> None:
    assert "at least 2" in _err(capsys, _npy(tmp_path / "one.npy", walking_yup(1)))


@pytest.mark.parametrize("scale,tall", [(60.0, "m tall"), (0.006, "m tall")])
def test_absurd_subject_size_in_npy(tmp_path, capsys, scale, tall) -> None:
    msg = _err(capsys, _npy(tmp_path / "s.npy", walking_yup(30) * scale))
    assert tall in msg and "units?" in msg and "--units" in msg


@pytest.mark.parametrize("scale", [10000.0, 0.01])  # 100 m tall in cm; 1 cm tall in m
def test_absurd_skeleton_size_in_bvh(tmp_path, capsys, scale) -> None:
    (tmp_path / "s.bvh").write_text(bvh_text(scale=scale))
    msg = _err(capsys, tmp_path / "s.bvh")
    assert "units?" in msg and "--units" in msg


@pytest.mark.parametrize("declared", [25, 4, -4])
def test_bvh_frames_line_disagreeing_with_the_rows(tmp_path, capsys, declared) -> None:
    """Issue 20: 'Frames: 10' with 189 rows read 10 frames, 'Frames: -4' dropped the last 4. The
    rows are read, with a warning giving both counts (a negative count too: the data is whole rows);
    --strict refuses."""
    import warnings

    from motion2robot.errors import InputWarning
    from motion2robot.motion.bvh import parse_bvh

    path = tmp_path / "t.bvh"
    path.write_text(bvh_text(frames=10, declared_frames=declared))
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        clip = parse_bvh(path)
    assert clip.values.shape[0] == 10
    assert len(w) == 1 and issubclass(w[0].category, InputWarning)
    assert f"'Frames: {declared}' but the MOTION data holds 10 frames" in str(w[0].message)
    with pytest.raises(InputFileError, match=f"'Frames: {declared}' but the MOTION data holds 10 frames"):
        parse_bvh(path, strict=True)
    code = main(["inspect", str(path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 0 and len(err) == 1 and err[0].startswith("motion2robot: warning: ") and "10 frames" in err[0]


@pytest.mark.parametrize("value", ["nan", "inf", "1e308"])
def test_a_bvh_value_that_is_no_number_is_named_plainly(tmp_path, capsys, value) -> None:
    text = bvh_text(frames=10)
    head, motion = text.split("MOTION\n")
    rows = motion.splitlines()
    cells = rows[5].split()
    cells[4] = value  # frame 3, channel 5
    rows[5] = " ".join(cells)
    (tmp_path / "t.bvh").write_text(head + "MOTION\n" + "\n".join(rows) + "\n")
    err = _err(capsys, tmp_path / "t.bvh")
    assert f"frame 3, channel 5 of the MOTION data is {float(value):g} (" in err and "np." not in err


def test_truncated_mid_row_bvh(tmp_path, capsys) -> None:
    (tmp_path / "t.bvh").write_text(bvh_text(frames=10)[:-40])
    assert "truncated" in _err(capsys, tmp_path / "t.bvh")


def test_unknown_bvh_skeleton(tmp_path, capsys) -> None:
    names = tuple(f"bone{i}" for i in range(22))
    (tmp_path / "u.bvh").write_text(bvh_text(names=names))
    msg = _err(capsys, tmp_path / "u.bvh")
    assert "unknown skeleton" in msg and "pelvis" in msg and "bone0" in msg


def test_results_lengths_exceed_array(tmp_path, capsys) -> None:
    motion = walking_yup(40).transpose(1, 2, 0)[None].repeat(2, axis=0)
    d = {"motion": motion, "text": ["a", "b"], "lengths": np.array([40, 55]), "num_samples": 2}
    np.save(tmp_path / "results.npy", np.array(d, dtype=object), allow_pickle=True)
    msg = _err(capsys, tmp_path / "results.npy")
    assert "lengths exceed" in msg and "[1]" in msg and "55" in msg


def test_results_that_are_fine_read(tmp_path, capsys) -> None:
    motion = walking_yup(40).transpose(1, 2, 0)[None].repeat(2, axis=0)
    d = {"motion": motion, "text": ["walk", "stroll"], "lengths": np.array([40, 25])}
    np.save(tmp_path / "results.npy", np.array(d, dtype=object), allow_pickle=True)
    assert main(["inspect", str(tmp_path / "results.npy")]) == 0
    out = capsys.readouterr().out
    assert "mdm_results" in out and '"stroll"' in out and "25 at 20 fps" in out


def test_directory_given_as_file(tmp_path, capsys) -> None:
    (tmp_path / "clip.npy").mkdir()
    assert "is a directory" in _err(capsys, tmp_path / "clip.npy")
    (tmp_path / "empty").mkdir()
    assert "directory without motion files" in _err(capsys, tmp_path / "empty")


def test_missing_file_and_unknown_extension(tmp_path, capsys) -> None:
    assert "does not exist" in _err(capsys, tmp_path / "nope.npy")
    (tmp_path / "x.fbx").write_bytes(b"Kaydara FBX Binary")
    assert "unknown format" in _err(capsys, tmp_path / "x.fbx")


class _Evil:
    def __init__(self, marker: Path):
        self.marker = marker

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


def test_pickle_that_would_run_code_is_refused(tmp_path, capsys) -> None:
    marker = tmp_path / "PWNED"
    payload = {"motion": np.zeros((1, 22, 3, 5)), "text": [_Evil(marker)], "lengths": np.array([5])}
    path = tmp_path / "results.npy"
    np.save(path, np.array(payload, dtype=object), allow_pickle=True)
    # control: an unrestricted load of the same file DOES run the command (in a child process)
    control = tmp_path / "CTRL0"  # same length as PWNED: the pickle string keeps its size
    (tmp_path / "control.npy").write_bytes(path.read_bytes().replace(b"PWNED", b"CTRL0"))
    subprocess.run([sys.executable, "-c", "import numpy, sys; numpy.load(sys.argv[1], allow_pickle=True)",
                    str(tmp_path / "control.npy")], check=False, capture_output=True, timeout=60)
    assert control.exists()
    msg = _err(capsys, path)
    assert "refused: the file's pickle asks for" in msg and "system" in msg
    assert not marker.exists()
    with pytest.raises(InputFileError, match="refused"):
        read_motion(path)
    assert not marker.exists()


def test_plain_pickle_with_reduce_to_eval_is_refused(tmp_path) -> None:
    marker = tmp_path / "PWNED2"

    class Evil2:
        def __reduce__(self):
            return (eval, (f"open({str(marker)!r}, 'w').close()",))

    (tmp_path / "x.pkl").write_bytes(pickle.dumps({"smpl_poses": Evil2()}))
    with pytest.raises(InputFileError, match=r"asks for builtins\.eval"):
        read_motion(tmp_path / "x.pkl")
    assert not marker.exists()

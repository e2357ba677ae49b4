"""Plausibility warnings, one line each (issue 20: upside-down, complex-valued and 500 m teleport
motions were accepted without a word), and the cap on .npz members."""

from __future__ import annotations

import io
import zipfile

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.errors import InputFileError
from motion2robot.motion.archive import read_npz_members
from tests.test_motion_support import walking_yup


def _warnings(capsys, path, *extra):
    code = main(["inspect", str(path), *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 0, err
    assert all(line.startswith("motion2robot: warning: ") for line in err), err
    return err


def test_a_clean_clip_gets_no_warning(tmp_path, capsys):
    np.save(tmp_path / "m.npy", walking_yup(40))
    assert _warnings(capsys, tmp_path / "m.npy") == []


def test_upside_down(tmp_path, capsys):
    j = walking_yup(40)
    np.save(tmp_path / "m.npy", j)
    err = _warnings(capsys, tmp_path / "m.npy", "--up=-y")  # the wrong way up on purpose
    assert len(err) == 1 and "upside down in 100% of frames" in err[0]


def test_teleport_of_500_m(tmp_path, capsys):
    j = walking_yup(40)
    j[20:, :, 0] += 500.0
    np.save(tmp_path / "m.npy", j)
    err = _warnings(capsys, tmp_path / "m.npy")
    assert len(err) == 1 and "jumps 500 m between frames 19 and 20" in err[0]


def test_absurd_speed_names_the_keypoint(tmp_path, capsys):
    j = walking_yup(40)
    j[10, 21] += [3.0, 0.0, 0.0]  # right wrist 3 m away for one frame at 20 fps: 60 m/s
    np.save(tmp_path / "m.npy", j)
    err = _warnings(capsys, tmp_path / "m.npy")
    assert len(err) == 1 and "right_wrist moves at" in err[0] and "frames 9 and 10" in err[0]


def test_complex_values_with_zero_imaginary_parts_are_read_with_a_warning(tmp_path, capsys):
    np.save(tmp_path / "m.npy", walking_yup(40).astype(np.complex128))
    err = _warnings(capsys, tmp_path / "m.npy")
    assert len(err) == 1 and "complex numbers (all imaginary parts 0)" in err[0]


def test_npz_member_expanding_past_the_cap_is_refused_before_decompression(tmp_path):
    p = tmp_path / "bomb.npz"
    buf = io.BytesIO()
    np.save(buf, np.zeros((200_000, 22, 3), np.float32))  # 53 MB of zeros, a few kB compressed
    with zipfile.ZipFile(p, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr("joints.npy", buf.getvalue())
    assert p.stat().st_size < 200_000
    with pytest.raises(InputFileError, match=r"member joints.npy expands to 53 MB, above the 10 MB allowed"):
        read_npz_members(p, ("joints",), max_bytes=10_000_000)
    assert read_npz_members(p, ("joints",))["joints"].shape == (200_000, 22, 3)  # under the default cap

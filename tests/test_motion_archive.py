""".npz archives are read without trusting them (issue 20: a 2.3 MB npz expanded to 528 MB and took
17 s and 3.5 GB): every member is capped in its expanded size before it is decompressed, a header
promising more data than the member holds is refused before anything is allocated (it was a
MemoryError, exit 3), and every reader of .npz files a user hands over goes through the cap."""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.errors import InputFileError
from motion2robot.motion import archive
from motion2robot.motion.archive import npz_member_shape, read_npz_members
from tests.test_motion_support import walking_yup


def _header(shape: tuple[int, ...], descr: str = "<f4") -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": descr, "fortran_order": False, "shape": shape})
    return buf.getvalue()


def zero_bomb(path: Path, shape: tuple[int, ...], member: str = "joints", **others: np.ndarray) -> Path:
    """An .npz whose ``member`` is ``shape`` float32 zeros, deflated at level 1 (528 MB -> 2.3 MB)."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        with z.open(f"{member}.npy", "w", force_zip64=True) as m:
            m.write(_header(shape))
            left, chunk = int(np.prod(shape)) * 4, bytes(1 << 22)
            while left:
                m.write(chunk[: min(left, len(chunk))])
                left -= min(left, len(chunk))
        for k, v in others.items():
            buf = io.BytesIO()
            np.save(buf, v)
            z.writestr(f"{k}.npy", buf.getvalue())
    return path


def _one_line(capsys, argv: list[str]) -> str:
    code = main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("motion2robot: error: "), (code, err)
    return err[0]


def test_the_issues_528_mb_archive_is_refused_before_decompression(tmp_path, capsys):
    """By inspect, and by a batch, whose clip count reads the member's header alone (it loaded the
    whole member) and whose worker gives the file an error row."""
    folder = tmp_path / "clips"
    folder.mkdir()
    p = zero_bomb(folder / "bomb.npz", (2_000_000, 22, 3), fps=np.asarray(20.0))
    assert p.stat().st_size < 3_000_000
    err = _one_line(capsys, ["inspect", str(p)])
    assert str(p) in err and "member joints.npy expands to 528 MB, above the 268 MB allowed" in err
    assert npz_member_shape(p, "joints") == (2_000_000, 22, 3)
    np.save(folder / "ok.npy", walking_yup(30))
    out = tmp_path / "r.jsonl"
    assert main(["batch", str(folder), "--robot", "op3", "--out", str(out), "--no-physics", "-q"]) == 0
    rows = {Path(r["path"]).name: r for r in map(json.loads, out.read_text().splitlines())}
    assert set(rows) == {"bomb.npz", "ok.npy"} and "expands to 528 MB" in rows["bomb.npz"]["error"]


def test_a_header_promising_more_than_the_member_holds_is_refused_before_allocation(tmp_path, capsys):
    p = tmp_path / "liar.npz"
    with zipfile.ZipFile(p, "w") as z:
        z.writestr("joints.npy", _header((10_000_000_000, 22, 3)) + bytes(4096))
        z.writestr("fps.npy", _header(()) + np.float32(20.0).tobytes())
    with pytest.raises(InputFileError, match=r"promises \(10000000000, 22, 3\) float32 = 2640000000000 bytes, it "
                                             r"holds 4096"):
        read_npz_members(p, ("joints",))
    with pytest.raises(InputFileError, match="promises"):
        npz_member_shape(p, "joints")
    assert "2640000000000 bytes" in _one_line(capsys, ["inspect", str(p)])  # was a MemoryError, exit 3


def test_members_read_back_exactly(tmp_path):
    a = np.arange(24, dtype=np.float64).reshape(2, 3, 4)
    np.savez_compressed(tmp_path / "m.npz", a=a, f=np.asfortranarray(a), s=np.array("op3"))
    m = read_npz_members(tmp_path / "m.npz", ("a", "f", "s", "absent"))
    assert set(m) == {"a", "f", "s"} and m.names == ["a", "f", "s"]
    assert np.array_equal(m["a"], a) and np.array_equal(m["f"], a) and str(m["s"]) == "op3"
    assert m["a"].flags.writeable
    assert npz_member_shape(tmp_path / "m.npz", "f") == (2, 3, 4) and npz_member_shape(tmp_path / "m.npz", "x") is None


def test_every_npz_reader_goes_through_the_cap(tmp_path, capsys, monkeypatch):
    """AMASS parameters, a body model and a robot motion handed to stream: with the cap lowered to
    20 kB, each refuses a member above it (each used np.load, uncapped)."""
    from tests.fuzz.corpus import robot_npz
    from tests.test_motion_body_model import smplh_fixture

    monkeypatch.setattr(archive, "MAX_MEMBER_BYTES", 20_000)
    amass = tmp_path / "amass.npz"
    np.savez(amass, poses=np.zeros((40, 156)), trans=np.zeros((40, 3)), mocap_framerate=np.asarray(30.0))  # 50 kB
    assert "member poses.npy expands to" in _one_line(capsys, ["inspect", str(amass)])
    small = tmp_path / "small.npz"
    np.savez(small, poses=np.zeros((10, 66)), trans=np.zeros((10, 3)), mocap_framerate=np.asarray(30.0))
    model = smplh_fixture(tmp_path / "model.npz")  # v_template 3.7 kB, J_regressor 62 kB
    err = _one_line(capsys, ["inspect", str(small), "--body-model", str(model)])
    assert str(model) in err and "member J_regressor.npy expands to" in err
    motion = robot_npz(tmp_path, "r.npz", frames=100)  # qpos 21.6 kB
    err = _one_line(capsys, ["stream", str(motion), "--dry-run", "--telemetry", str(tmp_path / "t.jsonl")])
    assert str(motion) in err and "member qpos.npy expands to" in err

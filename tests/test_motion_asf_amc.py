"""CMU ASF/AMC reader: the real take 01_01, the cross-check against its cgspeed BVH conversion,
skeleton lookup, the FK conventions, and bad input (one line on stderr, exit code 2)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.errors import InputFileError
from motion2robot.motion import KP, SMPL22, detect_format, read_motion, subject_height
from motion2robot.motion.asf_amc import euler_matrix, parse_asf
from motion2robot.motion.canonical import UNIT_SCALE
from tests._shared import MOTIONS, requires_shared

pytestmark = requires_shared

LOWER = ("pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2", "left_ankle",
         "right_ankle", "left_foot", "right_foot")
UPPER = ("neck", "left_collar", "right_collar", "head", "left_shoulder", "right_shoulder", "left_elbow",
         "right_elbow", "left_wrist", "right_wrist")  # all hang off the end of the thorax bone


@pytest.fixture(scope="module")
def take():
    return read_motion(MOTIONS / "cmu_asf_amc" / "01_01.amc")[0]


@pytest.fixture(scope="module")
def bvh():
    return read_motion(MOTIONS / "bvh" / "cmu_01_01.bvh")[0]


def _lines(rel: str) -> list[str]:
    return (MOTIONS / rel).read_text().splitlines()


def _short_take(folder: Path, frames: int = 12, name: str = "01_01.amc", edit=None) -> Path:
    """The first ``frames`` frames of 01_01.amc (4 header lines, then 30 lines per frame), with
    01.asf beside it; ``edit(lines)`` may change the lines (LF endings)."""
    lines = _lines("cmu_asf_amc/01_01.amc")[: 4 + 30 * frames]
    if edit is not None:
        edit(lines)
    (folder / name).write_text("\n".join(lines) + "\n")
    shutil.copy(MOTIONS / "cmu_asf_amc" / "01.asf", folder / "01.asf")
    return folder / name


def _err(capsys, *argv) -> str:
    code = main(["inspect", *map(str, argv)])
    out = capsys.readouterr()
    lines = out.err.strip().splitlines()
    assert code == 2, out
    assert len(lines) == 1 and lines[0].startswith("motion2robot: error: "), out.err
    return lines[0]


def test_reads_the_cmu_take(take) -> None:
    assert detect_format(MOTIONS / "cmu_asf_amc" / "01_01.amc") == "asf_amc"
    assert take.num_frames == 2751 and take.fps == 120.0
    assert 1.4 <= subject_height(take) <= 2.0, subject_height(take)
    m = take.meta
    assert (m["format"], m["skeleton"], m["units"], m["up_axis"]) == ("asf_amc", "cmu", "cmu", "y")
    assert m["asf"].endswith("01.asf") and m["first_frame"] == 1
    p = take.positions  # canonical: floor at 0, pelvis over the origin, facing +x (left = +y)
    assert abs(p[:, [KP["left_ankle"], KP["right_ankle"], KP["left_foot"], KP["right_foot"]], 2].min()) < 1e-9
    assert np.allclose(p[0, KP["pelvis"], :2], 0.0)
    assert p[0, KP["left_hip"], 1] > p[0, KP["right_hip"], 1]


def test_matches_the_cgspeed_bvh_of_the_same_take(take, bvh) -> None:
    """Lower body: the same points. Upper body: the cgspeed conversion drops the thorax bone
    (its Neck and shoulders sit at the thorax START), so every keypoint above it is off by
    exactly the thorax length. Measured: lower body max 1.1e-5 m; upper body 0.11655 m +- 1e-5;
    mean over all 22 keypoints 5.56 cm."""
    assert bvh.num_frames == take.num_frames == 2751
    d = np.linalg.norm(take.positions - bvh.positions, axis=-1)
    assert d[:, [KP[k] for k in LOWER]].max() < 1e-3
    thorax = parse_asf(MOTIONS / "cmu_asf_amc" / "01.asf").bones["thorax"].length * UNIT_SCALE["cmu"]
    assert thorax == pytest.approx(0.1165, abs=1e-3)
    assert np.abs(d[:, [KP[k] for k in UPPER]] - thorax).max() < 1e-3


def test_without_the_thorax_length_it_reproduces_the_bvh(tmp_path, bvh) -> None:
    """The strong FK check: with the thorax length set to 0 (what the cgspeed BVH did), all 22
    keypoints agree over all 2751 frames (measured: mean 2.1e-6 m, max 7.2e-6 m)."""
    text = (MOTIONS / "cmu_asf_amc" / "01.asf").read_text()
    i = text.index("name thorax")
    j = text.index("length", i)
    k = text.index("\n", j)
    (tmp_path / "no_thorax.asf").write_text(text[:j] + "length 0" + text[k:])
    m = read_motion(MOTIONS / "cmu_asf_amc" / "01_01.amc", skeleton=tmp_path / "no_thorax.asf")[0]
    d = np.linalg.norm(m.positions - bvh.positions, axis=-1)
    assert d.max() < 1e-4 and d.shape == (2751, len(SMPL22))


def test_cli_inspect_reads_the_take(capsys) -> None:
    assert main(["inspect", str(MOTIONS / "cmu_asf_amc" / "01_01.amc")]) == 0
    out = capsys.readouterr().out
    assert "format asf_amc" in out and "2751 at 120 fps" in out


def test_general_parser_matches_fast_path(tmp_path) -> None:
    """A frame listing its bones in another order (valid AMC) goes through the line-by-line
    parser and gives the same motion; LF endings read like CRLF."""
    ref = read_motion(_short_take(tmp_path))[0]

    def shuffle(lines: list[str]) -> None:
        lines[4 + 30 * 3 + 1: 4 + 30 * 4] = lines[4 + 30 * 3 + 1: 4 + 30 * 4][::-1]
    other = tmp_path / "b"
    other.mkdir()
    m = read_motion(_short_take(other, edit=shuffle))[0]
    assert np.allclose(m.positions, ref.positions, atol=1e-12) and m.num_frames == 12


def test_skeleton_lookup_by_stem_prefix(tmp_path) -> None:
    amc = _short_take(tmp_path, name="01_07.amc")
    (tmp_path / "02.asf").write_text("not the one")
    assert read_motion(amc)[0].meta["asf"] == str(tmp_path / "01.asf")
    (tmp_path / "01.asf").rename(tmp_path / "subject.asf")
    (tmp_path / "02.asf").unlink()  # the only .asf left beside it
    assert read_motion(amc)[0].meta["asf"] == str(tmp_path / "subject.asf")


def test_length_unit_is_read_from_the_asf(tmp_path) -> None:
    """':units length 1' means 1 unit = 1 inch: the same numbers make a body 0.45 x as tall."""
    amc = _short_take(tmp_path)
    ref = read_motion(amc)[0]
    asf = tmp_path / "01.asf"
    asf.write_text(asf.read_text().replace("length 0.45", "length 1.0"))
    m = read_motion(amc)[0]
    assert m.meta["units"] == "inch"
    assert np.allclose(m.positions, ref.positions * 0.45, atol=1e-9)


def test_euler_order_is_first_listed_first() -> None:
    a = np.array([[30.0, -50.0, 70.0]])
    rx, ry, rz = (euler_matrix(np.array([[v]]), ax)[0] for v, ax in zip(a[0], "XYZ"))
    assert np.allclose(euler_matrix(a, "XYZ")[0], rz @ ry @ rx)
    assert np.allclose(euler_matrix(a[:, ::-1], "ZYX")[0], rx @ ry @ rz)
    assert np.allclose(rz @ [1.0, 0.0, 0.0], [np.cos(np.radians(70)), np.sin(np.radians(70)), 0.0])


def _drop_tail(n: int):
    return lambda lines: lines.__delitem__(slice(len(lines) - n, None))


def _replace(old: str, new: str, frame: int | None = None):
    def edit(lines: list[str]) -> None:
        for i, ln in enumerate(lines):
            if (frame is None or (i - 4) // 30 == frame - 1) and ln.split()[:1] == [old]:
                lines[i] = new + ln[len(old):]
    return edit


@pytest.mark.parametrize("edit, expected", [
    (_drop_tail(5), "is truncated: the last frame (12) lacks 5 of 29 bones (lfemur, ltibia, lfoot, ltoes ...)"),
    (lambda ls: ls.__setitem__(-1, "ltoes"), "is truncated: frame 12 gives 0 values for bone 'ltoes'"),
    (_replace("rtoes", "rtoez", frame=6), "bone 'rtoez' is not in the skeleton"),
    (_replace("5", "7", frame=5), "non-contiguous frame numbers (4 is followed by 7)"),
    (_replace("lfemur", "lfemur 1.0", frame=3), "frame 3 gives 4 values for bone 'lfemur'"),
    (lambda ls: ls.__setitem__(4 + 30 + 7, "head 1.0 x 2.0"), "non-numeric values for bone 'head'"),
    (lambda ls: ls.__delitem__(4 + 30 * 6 + 8), "frame 7 lists bone 'rclavicle' not at all"),
])
def test_bad_amc(tmp_path, capsys, edit, expected) -> None:
    msg = _err(capsys, _short_take(tmp_path, edit=edit))
    assert expected in msg and str(tmp_path / "01_01.amc") in msg


def test_amc_without_asf(tmp_path, capsys) -> None:
    amc = _short_take(tmp_path)
    (tmp_path / "01.asf").unlink()
    msg = _err(capsys, amc)
    assert "without its ASF skeleton (no 01_01.asf or 01.asf beside it)" in msg and "--skeleton" in msg


def test_asf_alone_is_refused(tmp_path, capsys) -> None:
    _short_take(tmp_path)
    msg = _err(capsys, tmp_path / "01.asf")
    assert "is an ASF skeleton without motion" in msg and "01_01.amc" in msg


@pytest.mark.parametrize("old, new, expected", [
    (":hierarchy", ":hierarchx", "no :hierarchy section"),
    ("lfemur ltibia", "lfemur ltibiaa", "names bone 'ltibiaa', which :bonedata does not define"),
    ("dof rx ry rz", "dof rx ry tz", "only rotational dofs"),
    ("axis 0 0 20  XYZ", "axis 0 0 XYZ", "malformed 'axis'"),
])
def test_bad_asf(tmp_path, old, new, expected) -> None:
    amc = _short_take(tmp_path)
    asf = tmp_path / "01.asf"
    text = asf.read_text()
    assert old in text
    asf.write_text(text.replace(old, new, 1))
    with pytest.raises(InputFileError) as err:
        read_motion(amc)
    assert expected in str(err.value) and str(asf) in str(err.value) and "\n" not in str(err.value)


def test_unmapped_keypoints_name_the_fix(tmp_path, capsys) -> None:
    """A non-CMU bone name (here lfemur -> lthigh in both files) leaves keypoints unmapped."""
    amc = _short_take(tmp_path, edit=_replace("lfemur", "lthigh"))
    asf = tmp_path / "01.asf"
    asf.write_text(asf.read_text().replace("lfemur", "lthigh"))
    msg = _err(capsys, amc)
    assert "cannot map" in msg and "left_hip" in msg and "--name-map" in msg and str(amc) in msg

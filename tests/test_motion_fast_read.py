"""The fast .npy read path gives exactly what the straightforward computation gives.

The reference below is the reader's pipeline written with numpy's generic tools (np.load,
np.percentile, np.median, (T, 22, 3) @ (3, 3) products, slice updates), as the readers computed
it before the fast path; read_motion must return the same positions, contacts and meta.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from numpy.lib import format as npformat

from motion2robot.errors import InputFileError
from motion2robot.motion.canonical import FOOT_KPS, HEIGHT_BOUNDS, canonical_positions, heading_yaw, rot_z, up_rotation
from motion2robot.motion.height import BONE_FACTOR, HEAD_TOP_FACTOR, _median_axis0, _percentile, stature
from motion2robot.motion.human import KP
from motion2robot.motion.options import ReadOptions
from motion2robot.motion.read import _read_file, detect_format, read_motion
from motion2robot.motion.safe_pickle import load_npy
from tests._shared import MOTIONS, requires_shared

_LEGS = (("left_hip", "left_knee"), ("left_knee", "left_ankle"),
         ("right_hip", "right_knee"), ("right_knee", "right_ankle"))
_SPINE = (("pelvis", "spine1"), ("spine1", "spine2"), ("spine2", "spine3"), ("spine3", "neck"), ("neck", "head"))
_FEET = list(FOOT_KPS)


def _ref_stature(pos: np.ndarray) -> float:
    h = pos[..., 2]
    posture = float(np.percentile(h[:, KP["head"]] - h[:, _FEET].min(axis=1), 98)) * HEAD_TOP_FACTOR
    d = pos[:, [KP[a] for a, _ in _LEGS + _SPINE]] - pos[:, [KP[b] for _, b in _LEGS + _SPINE]]
    lengths = np.median(np.sqrt(np.einsum("tbi,tbi->tb", d, d)), axis=0)
    bone = float(lengths[: len(_LEGS)].sum() / 2.0 + lengths[len(_LEGS):].sum()) * BONE_FACTOR
    return max(posture, bone)


def _ref_canonical(raw: np.ndarray) -> np.ndarray:
    """HumanML3D-space (y up, metres) joints -> canonical positions, the slow way."""
    pos = np.asarray(raw, dtype=np.float64)
    assert np.isfinite(pos).all()
    pos = pos @ up_rotation("y").T
    height = _ref_stature(pos)
    assert HEIGHT_BOUNDS[0] <= height <= HEIGHT_BOUNDS[1]
    assert stature(pos) == height
    p = pos.copy()
    p[..., 2] -= float(p[:, _FEET, 2].min())
    p = p @ rot_z(-heading_yaw(p)).T
    p[..., :2] -= p[0, KP["pelvis"], :2]
    np.testing.assert_array_equal(canonical_positions(pos), p)
    return p


def _ref_clips(path: Path) -> list[tuple[np.ndarray, dict]]:
    """(raw (T, 22, 3) clip, meta it must carry) for every clip of a shared file."""
    fmt = detect_format(path)
    if fmt == "mdm_results":
        d = load_npy(path)  # restricted unpickler: dict of arrays
        motion = np.transpose(d["motion"], (0, 3, 1, 2))
        return [(motion[i, : int(d["lengths"][i])], {"format": fmt, "clip": i, "prompt": str(d["text"][i])})
                for i in range(len(motion))]
    arr = np.load(path, allow_pickle=False)
    if fmt == "mdm_array":
        return [(c, {"format": fmt, "clip": i}) for i, c in enumerate(np.transpose(arr, (0, 3, 1, 2)))]
    assert fmt == "humanml3d_joints" and arr.ndim == 3
    return [(arr[:, :22], {"format": fmt, "clip": 0})]


def _shared_files() -> list[Path]:
    if MOTIONS is None:
        return []
    return sorted((MOTIONS / "humanml3d_joints").glob("*.npy")) + sorted((MOTIONS / "mdm_results").glob("*.npy"))


@requires_shared
@pytest.mark.parametrize("path", _shared_files(), ids=lambda p: p.name)
def test_fast_read_equals_reference(path: Path) -> None:
    got = read_motion(path)
    general = _read_file(path, detect_format(path), ReadOptions())  # load_npy + dispatch, no fast path
    ref = _ref_clips(path)
    assert len(got) == len(general) == len(ref) > 0
    for m, g, (raw, meta) in zip(got, general, ref):
        np.testing.assert_array_equal(m.positions, _ref_canonical(raw))
        np.testing.assert_array_equal(m.positions, g.positions)
        assert m.contacts is None and g.contacts is None
        assert dict(m.meta) == dict(g.meta)
        assert m.fps == 20.0
        expected = {"source": str(path), "up_axis": "y", "units": "m", "source_fps": 20.0, **meta}
        assert {k: m.meta.get(k) for k in expected} == expected


@requires_shared
def test_fast_read_of_a_folder_equals_per_file() -> None:
    folder = MOTIONS / "humanml3d_joints"
    per_file = [m for f in sorted(folder.glob("*.npy")) for m in read_motion(f)]
    whole = read_motion(folder)
    assert len(whole) == len(per_file)
    for a, b in zip(whole, per_file):
        np.testing.assert_array_equal(a.positions, b.positions)
        assert dict(a.meta) == {**b.meta, "folder": str(folder), "clip": a.meta["clip"]}


def _npy_bytes(arr: np.ndarray, version: tuple[int, int] | None = None) -> bytes:
    buf = io.BytesIO()
    npformat.write_array(buf, arr, version=version, allow_pickle=False)
    return buf.getvalue()


@pytest.mark.parametrize("arr", [
    np.arange(24, dtype=np.float32).reshape(2, 4, 3),
    np.asfortranarray(np.arange(12.0).reshape(3, 4)),
    np.arange(6, dtype=">f8").reshape(2, 3),
    np.array([True, False, True]),
    np.array(3.5),
    np.zeros((0, 22, 3), np.float32),
    np.zeros(5, dtype=[("a", "<f4"), ("b", "<i2")]),  # list descr: numpy's own header parser
], ids=["f32", "fortran", "big-endian", "bool", "0-d", "empty", "structured"])
@pytest.mark.parametrize("version", [None, (2, 0)])
def test_load_npy_equals_np_load(tmp_path: Path, arr: np.ndarray, version) -> None:
    p = tmp_path / "a.npy"
    p.write_bytes(_npy_bytes(arr, version))
    got, want = load_npy(p), np.load(p, allow_pickle=False)
    assert got.dtype == want.dtype and got.shape == want.shape
    assert got.flags.writeable and got.flags.f_contiguous == want.flags.f_contiguous
    np.testing.assert_array_equal(got, want)


def test_load_npy_refuses_truncated_and_odd_headers(tmp_path: Path) -> None:
    data = _npy_bytes(np.zeros((10, 22, 3), np.float32))
    (tmp_path / "t.npy").write_bytes(data[:-7])
    with pytest.raises(InputFileError, match="damaged"):
        load_npy(tmp_path / "t.npy")
    with pytest.raises(InputFileError, match="damaged"):
        read_motion(tmp_path / "t.npy")
    huge = data.replace(b"(10, 22, 3), }   ", b"(999999999, 3), }")
    assert len(huge) == len(data) and huge != data
    (tmp_path / "huge.npy").write_bytes(huge)  # a header promising 12 GB: refused, not allocated
    with pytest.raises(InputFileError, match="damaged.*truncated"):
        load_npy(tmp_path / "huge.npy")
    (tmp_path / "h.npy").write_bytes(data[:20])
    with pytest.raises(InputFileError, match="broken .npy header"):
        read_motion(tmp_path / "h.npy")
    (tmp_path / "v.npy").write_bytes(data[:6] + b"\x09\x00" + data[8:])
    with pytest.raises(InputFileError, match="broken .npy header"):
        load_npy(tmp_path / "v.npy")


def test_order_statistics_equal_numpy() -> None:
    rng = np.random.default_rng(7)
    for n in [1, 2, 3, 4, 5, 50, 51, 196, 197]:
        for _ in range(20):
            x = rng.normal(size=n)
            if n > 3:
                x[: n // 3] = x[n // 2]  # ties
            for q in (0, 37, 50, 98, 99.9, 100):
                assert _percentile(x, q) == float(np.percentile(x, q))
            m = np.abs(rng.normal(size=(n, 9)))
            np.testing.assert_array_equal(_median_axis0(m), np.median(m, axis=0))
    assert np.isnan(_percentile(np.array([1.0, np.nan, 2.0]), 98))
    assert np.isnan(_median_axis0(np.array([[1.0], [np.nan]]))[0])

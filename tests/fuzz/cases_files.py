"""Corpus cases: malformed motion files of every format, and bad read options."""

from __future__ import annotations

import io
import os
import pickle
import struct
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from tests.fuzz.corpus import GOOD_BVH, J, bvh, case, inspect, mdm, npy, npy_header, npz, pickled, text
from tests.test_motion_support import bvh_text, walking_yup

# -- .npy ------------------------------------------------------------------------------------
case("npy: empty file")(lambda d: inspect(text(d, "e.npy", b"")))
case("npy: text in a .npy")(lambda d: inspect(text(d, "t.npy", "hello\n")))
case("npy: magic only")(lambda d: inspect(text(d, "m.npy", b"\x93NUMPY")))
case("npy: header cut")(lambda d: inspect(text(d, "m.npy", b"\x93NUMPY\x01\x00\x76\x00{'descr': '<f4'")))
case("npy: structured dtype")(lambda d: inspect(npy_header(d, "{'descr': [('a', '<f4'), ('b', '<f4')], "
                                                          "'fortran_order': False, 'shape': (30, 22), }", b"\0" * 8)))
case("npy: negative shape")(lambda d: inspect(npy_header(d, "{'descr': '<f4', 'fortran_order': False, "
                                                        "'shape': (-30, 22, 3), }", b"\0" * 64)))
case("npy: huge shape, little data")(lambda d: inspect(npy_header(d, "{'descr': '<f4', 'fortran_order': False, "
                                                                 "'shape': (10000000000, 22, 3), }", b"\0" * 64)))
case("npy: header not a dict")(lambda d: inspect(npy_header(d, "[1, 2, 3]", b"")))
case("npy: header with code")(lambda d: inspect(npy_header(d, "__import__('os').system('true')", b"")))
case("npy: unknown descr")(lambda d: inspect(npy_header(d, "{'descr': '<q9', 'fortran_order': False, "
                                                       "'shape': (30, 22, 3), }", b"")))
case("npy: data shorter than header says")(lambda d: inspect(npy_header(
    d, "{'descr': '<f4', 'fortran_order': False, 'shape': (30, 22, 3), }", b"\0" * 400)))
case("npy: (T, 21, 3)")(lambda d: inspect(npy(d, np.zeros((30, 21, 3), np.float32))))
case("npy: (T, 262)")(lambda d: inspect(npy(d, np.zeros((30, 262), np.float32))))
case("npy: 1-D")(lambda d: inspect(npy(d, np.zeros(30, np.float32))))
case("npy: 0-d number")(lambda d: inspect(npy(d, np.array(3.0))))
case("npy: 0 frames")(lambda d: inspect(npy(d, np.zeros((0, 22, 3), np.float32))))
case("npy: 1 frame")(lambda d: inspect(npy(d, walking_yup(1))))
case("npy: all NaN")(lambda d: inspect(npy(d, np.full((30, 22, 3), np.nan))))
case("npy: inf")(lambda d: inspect(npy(d, np.where(np.arange(30)[:, None, None] == 3, np.inf, walking_yup(30)))))
case("npy: complex joints")(lambda d: inspect(npy(d, walking_yup(30) + 0.01j)))
case("npy: string array")(lambda d: inspect(npy(d, np.full((30, 22, 3), "a"))))
case("npy: bool array")(lambda d: inspect(npy(d, np.zeros((30, 22, 3), bool))))
case("npy: 3e38 value")(lambda d: inspect(npy(d, np.where(np.arange(30)[:, None, None] == 7, 3e38, walking_yup(30)))))
case("npy: all zeros")(lambda d: inspect(npy(d, np.zeros((30, 22, 3), np.float32))))
case("npy: (N, 22, 3, T) with N = 0")(lambda d: inspect(npy(d, np.zeros((0, 22, 3, 40), np.float32))))
case("npy: features all NaN")(lambda d: inspect(npy(d, np.full((30, 263), np.nan, np.float32))))
case("npy: features 3e38")(lambda d: inspect(npy(d, np.full((30, 263), 3e38, np.float32))))
case("npy: 263 stats file")(lambda d: inspect(npy(d, np.zeros(263, np.float32))))
case("npy: object array of a list")(lambda d: inspect(pickled(d, [1, 2, 3], "l.npy")))
case("npy: object array of a string")(lambda d: inspect(pickled(d, "motion", "s.npy")))
case("npy: pickled os.system")(lambda d: inspect(text(d, "evil.npy", _evil_npy())))


def _evil_npy() -> bytes:
    class Evil:
        def __reduce__(self):
            return (os.system, ("true",))
    buf = io.BytesIO()
    payload = pickle.dumps(Evil(), protocol=2)
    hdr = "{'descr': '|O', 'fortran_order': False, 'shape': (), }"
    h = hdr.encode()
    pad = 64 - (10 + len(h) + 1) % 64
    h = h + b" " * pad + b"\n"
    buf.write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(h)) + h + payload)
    return buf.getvalue()


# -- MDM results dicts -------------------------------------------------------------------------
def _mdm_edit(**changes: object) -> Callable[[Path], list[str]]:
    def build(d: Path) -> list[str]:
        r = mdm()
        for k, v in changes.items():
            if v is _DROP:
                r.pop(k)
            else:
                r[k] = v
        return inspect(pickled(d, r))
    return build


_DROP = object()
case("mdm: string lengths")(_mdm_edit(lengths="forty"))
case("mdm: lengths list of words")(_mdm_edit(lengths=["forty"]))
case("mdm: numeric text")(_mdm_edit(text=12345))
case("mdm: text list of numbers")(_mdm_edit(text=[1.5]))
case("mdm: text a dict")(_mdm_edit(text={"a": 1}))
case("mdm: fractional lengths")(_mdm_edit(lengths=np.array([20.5])))
case("mdm: no motion key")(_mdm_edit(motion=_DROP))
case("mdm: motion is a string")(_mdm_edit(motion="walk"))
case("mdm: motion wrong shape")(_mdm_edit(motion=np.zeros((1, 21, 3, 40), np.float32)))
case("mdm: motion NaN")(_mdm_edit(motion=np.full((1, 22, 3, 40), np.nan, np.float32)))
case("mdm: lengths longer than T")(_mdm_edit(lengths=np.array([400])))
case("mdm: negative lengths")(_mdm_edit(lengths=np.array([-5])))
case("mdm: lengths of another sample count")(_mdm_edit(lengths=np.array([40, 40, 40])))
case("mdm: non-string keys")(lambda d: inspect(pickled(d, {1: np.zeros((1, 22, 3, 40)), 2: "x"})))
case("mdm: tuple keys")(lambda d: inspect(pickled(d, {("motion",): np.zeros((1, 22, 3, 40))})))
case("mdm: empty dict")(lambda d: inspect(pickled(d, {})))
case("mdm: --clip 5 of 1")(lambda d: inspect(pickled(d, mdm()), "--clip", "5"))
case("mdm: --clip -5")(lambda d: inspect(pickled(d, mdm()), "--clip", "-5"))
case("mdm: --clip abc")(lambda d: inspect(pickled(d, mdm()), "--clip", "abc"))

# -- .npz ------------------------------------------------------------------------------------
case("npz: no arrays")(lambda d: inspect(npz(d)))
case("npz: joints, no fps")(lambda d: inspect(npz(d, joints=J)))
for _label, _fps in (("0", 0.0), ("negative", -20.0), ("NaN", np.nan), ("inf", np.inf), ("text", "twenty"),
                     ("array", np.array([20.0, 30.0])), ("huge", 1e300), ("tiny", 1e-300), ("bool", True)):
    case(f"npz: fps {_label}")(lambda d, f=_fps: inspect(npz(d, joints=J, fps=np.asarray(f))))
case("npz: object array member")(lambda d: inspect(npz(d, joints=np.array([J, "x"], dtype=object), fps=20.0)))
case("npz: joints wrong shape")(lambda d: inspect(npz(d, joints=np.zeros((30, 5)), fps=20.0)))
case("npz: joints NaN")(lambda d: inspect(npz(d, joints=np.full((30, 22, 3), np.nan), fps=20.0)))
case("npz: joints complex")(lambda d: inspect(npz(d, joints=J + 0.5j, fps=20.0)))
case("npz: joints text")(lambda d: inspect(npz(d, joints=np.full((30, 22, 3), "a"), fps=20.0)))
case("npz: 0 frames")(lambda d: inspect(npz(d, joints=np.zeros((0, 22, 3)), fps=20.0)))


def _corrupt_npz(d: Path, how: str) -> list[str]:
    p = npz(d, joints=J, fps=np.asarray(20.0))
    raw = bytearray(p.read_bytes())
    if how == "crc":
        i = raw.find(b"joints.npy") + 200
        raw[i] ^= 0xFF
    elif how == "truncated":
        raw = raw[: len(raw) // 2]
    elif how == "garbage":
        raw = bytearray(b"PK\x03\x04" + os.urandom(300))
    p.write_bytes(bytes(raw))
    return inspect(p)


case("npz: bad CRC")(lambda d: _corrupt_npz(d, "crc"))
case("npz: truncated member")(lambda d: _corrupt_npz(d, "truncated"))
case("npz: zip magic then garbage")(lambda d: _corrupt_npz(d, "garbage"))
case("npz: not a zip")(lambda d: inspect(text(d, "m.npz", "not a zip at all")))


def _member_text(d: Path) -> list[str]:
    p = d / "m.npz"
    with zipfile.ZipFile(p, "w") as z:
        z.writestr("joints.npy", "this is text")
        z.writestr("fps.npy", "20")
    return inspect(p)


case("npz: member is text")(_member_text)


def _bomb(d: Path, member: str = "joints", shape: tuple[int, ...] = (2_000_000, 22, 3)) -> Path:
    """Issue 20's archive: 2.3 MB that expands to 528 MB of float32 zeros (deflate level 1)."""
    p = d / "bomb.npz"
    with zipfile.ZipFile(p, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        buf = io.BytesIO()
        np.lib.format.write_array_header_1_0(buf, {"descr": "<f4", "fortran_order": False, "shape": shape})
        with z.open(f"{member}.npy", "w", force_zip64=True) as m:
            m.write(buf.getvalue())
            left, chunk = int(np.prod(shape)) * 4, bytes(1 << 22)
            while left:
                m.write(chunk[: min(left, len(chunk))])
                left -= min(left, len(chunk))
        z.writestr("fps.npy", _npy_bytes(np.asarray(20.0)))
    return p


def _liar(d: Path) -> list[str]:
    """A member whose header promises 2.6 TB and that holds 4 kB."""
    p = d / "liar.npz"
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f4", "fortran_order": False, "shape": (10**10, 22, 3)})
    with zipfile.ZipFile(p, "w") as z:
        z.writestr("joints.npy", buf.getvalue() + bytes(4096))
        z.writestr("fps.npy", _npy_bytes(np.asarray(20.0)))
    return inspect(p)


def _npy_bytes(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, a)
    return buf.getvalue()


case("npz: 2.3 MB expanding to 528 MB")(lambda d: inspect(_bomb(d)))
case("npz: member header promises 2.6 TB")(_liar)
# SMPL parameters read with an approximate skeleton and a warning; --strict refuses them without a model
case("npz: SMPL parameters under --strict")(lambda d: inspect(npz(d, poses=np.zeros((30, 156)), trans=np.zeros((30, 3)),
                                                                  mocap_framerate=np.asarray(60.0)), "--strict"))
case("npz: SMPL parameters, body model missing keys")(lambda d: inspect(
    npz(d, poses=np.zeros((30, 156)), trans=np.zeros((30, 3)), mocap_framerate=np.asarray(60.0)),
    "--body-model", str(npz(d, "model.npz", v_template=np.zeros((10, 3))))))

# -- BVH -------------------------------------------------------------------------------------
_HEAD, _MOTION = GOOD_BVH.split("MOTION\n")
_ROWS = _MOTION.splitlines()[2:]


def _bvh_motion(frames_line: str, time_line: str = "Frame Time: 0.033333", rows: list[str] | None = None) -> str:
    return _HEAD + "MOTION\n" + frames_line + "\n" + time_line + "\n" + "\n".join(_ROWS if rows is None else rows) + "\n"


case("bvh: HIERARCHY only")(lambda d: inspect(bvh(d, "HIERARCHY\n")))
case("bvh: no MOTION section")(lambda d: inspect(bvh(d, _HEAD)))
case("bvh: no frames")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 0", rows=[]))))
case("bvh: Frames: abc")(lambda d: inspect(bvh(d, _bvh_motion("Frames: abc"))))
case("bvh: Frame Time: 0")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 30", "Frame Time: 0"))))
case("bvh: Frame Time: -1")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 30", "Frame Time: -0.03"))))
case("bvh: Frame Time: nan")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 30", "Frame Time: nan"))))
case("bvh: Frame Time: inf")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 30", "Frame Time: inf"))))
case("bvh: Frame Time: text")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 30", "Frame Time: fast"))))
case("bvh: word in a row")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 30", rows=_ROWS[:5] + ["0 0 x"] + _ROWS[6:]))))
case("bvh: short row")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 30", rows=_ROWS[:5] + ["0 0 0"] + _ROWS[6:]))))
case("bvh: NaN in a row")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 30", rows=[r.replace("0.00000", "nan", 1)
                                                                                    for r in _ROWS]))))
case("bvh: inf in a row")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 30", rows=[r.replace("0.00000", "inf", 1)
                                                                                    for r in _ROWS]))))
case("bvh: 1e308 in a row")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 30", rows=[r.replace("0.00000", "1e308", 1)
                                                                                      for r in _ROWS]))))
case("bvh: Frames: -4 under --strict")(lambda d: inspect(bvh(d, _bvh_motion("Frames: -4")), "--strict"))
case("bvh: Frames: 10 of 30 under --strict")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 10")), "--strict"))
case("bvh: one frame")(lambda d: inspect(bvh(d, _bvh_motion("Frames: 1", rows=_ROWS[:1]))))
case("bvh: CHANNELS count wrong")(lambda d: inspect(bvh(d, GOOD_BVH.replace("CHANNELS 3 ", "CHANNELS 4 ", 1))))
case("bvh: CHANNELS count text")(lambda d: inspect(bvh(d, GOOD_BVH.replace("CHANNELS 3 ", "CHANNELS x ", 1))))
case("bvh: unknown channel")(lambda d: inspect(bvh(d, GOOD_BVH.replace("Zrotation", "Wrotation", 1))))
case("bvh: unbalanced braces")(lambda d: inspect(bvh(d, GOOD_BVH.replace("}", "", 3))))
case("bvh: no ROOT")(lambda d: inspect(bvh(d, GOOD_BVH.replace("ROOT", "BONE", 1))))
case("bvh: OFFSET with 2 values")(lambda d: inspect(bvh(d, GOOD_BVH.replace("OFFSET 0 0 0", "OFFSET 0 0", 1))))
case("bvh: OFFSET text")(lambda d: inspect(bvh(d, GOOD_BVH.replace("OFFSET 0 0 0", "OFFSET a b c", 1))))
case("bvh: binary garbage")(lambda d: inspect(text(d, "g.bvh", bytes(range(256)) * 4)))
case("bvh: UTF-16")(lambda d: inspect(text(d, "u.bvh", GOOD_BVH.encode("utf-16"))))
case("bvh: duplicate joint names")(lambda d: inspect(bvh(d, GOOD_BVH.replace("JOINT LeftUpLeg", "JOINT RightUpLeg", 1))))
case("bvh: unknown joint names")(lambda d: inspect(bvh(d, bvh_text(names=tuple(f"bone{i}" for i in range(22))))))
case("bvh: 5,000 nested joints")(lambda d: inspect(bvh(d, "HIERARCHY\n" + "".join(
    f"{'ROOT' if i == 0 else 'JOINT'} j{i}\n{{\nOFFSET 0 0 1\nCHANNELS 3 Zrotation Yrotation Xrotation\n" for i in range(5000))
    + "}\n" * 5000 + "MOTION\nFrames: 1\nFrame Time: 0.03\n" + " ".join(["0"] * 15000) + "\n")))
case("bvh: --units parsec")(lambda d: inspect(bvh(d, GOOD_BVH), "--units", "parsec"))
case("bvh: --up w")(lambda d: inspect(bvh(d, GOOD_BVH), "--up", "w"))
case("bvh: --name-map missing")(lambda d: inspect(bvh(d, GOOD_BVH), "--name-map", str(d / "none.toml")))
case("bvh: --name-map bad TOML")(lambda d: inspect(bvh(d, GOOD_BVH), "--name-map", str(text(d, "n.toml", "a = = b"))))
case("bvh: --name-map unknown keypoint")(lambda d: inspect(bvh(d, GOOD_BVH), "--name-map",
                                                          str(text(d, "n.toml", 'Hips = "tail"\n'))))
case("bvh: --name-map not strings")(lambda d: inspect(bvh(d, GOOD_BVH), "--name-map", str(text(d, "n.toml", "Hips = 3\n"))))

# -- ASF/AMC ---------------------------------------------------------------------------------
case("amc: no .asf beside it")(lambda d: inspect(text(d, "01_01.amc", ":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\n")))
case("amc: --skeleton missing")(lambda d: inspect(text(d, "01_01.amc", "1\nroot 0 0 0 0 0 0\n"), "--skeleton",
                                                 str(d / "none.asf")))
case("amc: garbage .asf")(lambda d: (text(d, "01.asf", "garbage\n" * 5), inspect(text(d, "01_01.amc", "1\nroot 0 0 0 0 0 0\n")))[1])
case("amc: binary .amc")(lambda d: (text(d, "01.asf", ":version 1.10\n"), inspect(text(d, "01_01.amc", bytes(range(256)))))[1])

# -- generic inputs and read options ---------------------------------------------------------
case("input: missing file")(lambda d: inspect(d / "none.npy"))
case("input: empty folder")(lambda d: (d.joinpath("empty").mkdir(), inspect(d / "empty"))[1])
case("input: folder without motions")(lambda d: (d.joinpath("f").mkdir(), text(d / "f", "a.txt", "x"), inspect(d / "f"))[2])
case("input: path under a file")(lambda d: inspect(text(d, "file.npy", "x") / "x.npy"))
case("input: unknown extension")(lambda d: inspect(text(d, "m.xyz", "x")))
case("input: /dev/null")(lambda d: inspect(Path("/dev/null")))
case("input: FIFO")(lambda d: (os.mkfifo(d / "f.npy"), inspect(d / "f.npy"))[1])
case("input: directory named x.npy")(lambda d: (d.joinpath("x.npy").mkdir(), inspect(d / "x.npy"))[1])
case("input: broken symlink")(lambda d: (os.symlink(d / "gone.npy", d / "l.npy"), inspect(d / "l.npy"))[1])
case("input: .pt file without torch")(lambda d: inspect(text(d, "m.pt", b"PK\x03\x04garbage")))
case("option: --format npz for a .npy")(lambda d: inspect(npy(d, J), "--format", "npz"))
case("option: --format bvh for a .npy")(lambda d: inspect(npy(d, J), "--format", "bvh"))
case("option: --format humanml3d_vecs for joints")(lambda d: inspect(npy(d, J), "--format", "humanml3d_vecs"))
case("option: --format mdm_results for joints")(lambda d: inspect(npy(d, J), "--format", "mdm_results"))
case("option: --format nonsense")(lambda d: inspect(npy(d, J), "--format", "nonsense"))
for _v in ("-5", "nan", "0", "inf", "abc", "1e9"):
    case(f"option: --source-fps {_v}")(lambda d, v=_v: inspect(npy(d, J), "--source-fps", v))
case("option: --mean missing")(lambda d: inspect(npy(d, np.zeros((30, 263), np.float32)), "--mean", str(d / "no.npy"),
                                                "--std", str(d / "no.npy")))
case("option: --mean wrong shape")(lambda d: inspect(npy(d, np.zeros((30, 263), np.float32)), "--mean",
                                                    str(npy(d, np.zeros(10), "mean.npy")), "--std",
                                                    str(npy(d, np.ones(263), "std.npy"))))
case("option: --std zeros")(lambda d: inspect(npy(d, np.zeros((30, 263), np.float32)), "--mean",
                                             str(npy(d, np.zeros(263), "mean.npy")), "--std",
                                             str(npy(d, np.zeros(263), "std.npy"))))
case("option: --mean text")(lambda d: inspect(npy(d, np.zeros((30, 263), np.float32)), "--mean",
                                             str(text(d, "mean.npy", "x")), "--std", str(npy(d, np.ones(263), "std.npy"))))
case("option: --plot under a file")(lambda d: inspect(npy(d, J), "--plot", str(text(d, "f", "x") / "p.png")))
case("option: --plot is a directory")(lambda d: inspect(npy(d, J), "--plot", str(d)))


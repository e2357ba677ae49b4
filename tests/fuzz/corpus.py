"""A corpus of malformed inputs a user can hand motion2robot: broken motion files of every format,
broken robot configs, bad options. Every case must end as one ``motion2robot: error: ...`` line
and exit code 2 (issue 20, item 7). ``CASES`` lists them; each builds its files in a directory
and returns the command line.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tests.test_motion_support import bvh_text, walking_yup

ROOT = Path(__file__).resolve().parents[2]
OP3_TOML = ROOT / "robots" / "op3" / "op3.toml"


@dataclass(frozen=True)
class Case:
    name: str
    build: Callable[[Path], list[str]]


CASES: list[Case] = []


def case(name: str) -> Callable:
    def deco(fn: Callable[[Path], list[str]]) -> Callable[[Path], list[str]]:
        CASES.append(Case(name, fn))
        return fn
    return deco


# -- helpers ---------------------------------------------------------------------------------
def npy(d: Path, arr: np.ndarray, name: str = "m.npy") -> Path:
    p = d / name
    np.save(p, arr, allow_pickle=arr.dtype.hasobject)
    return p


def npy_header(d: Path, header: str, data: bytes = b"", name: str = "m.npy") -> Path:
    h = header.encode("latin1")
    pad = 64 - (10 + len(h) + 1) % 64
    h = h + b" " * pad + b"\n"
    p = d / name
    p.write_bytes(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(h)) + h + data)
    return p


def pickled(d: Path, obj: object, name: str = "results.npy") -> Path:
    """An object .npy like MDM's results.npy holding ``obj``."""
    arr = np.empty((), dtype=object)
    arr[()] = obj
    return npy(d, arr, name)


def npz(d: Path, name: str = "m.npz", **arrays: object) -> Path:
    p = d / name
    np.savez(p, **arrays)
    return p


def mdm(n: int = 1, t: int = 40) -> dict:
    motion = np.stack([walking_yup(t).transpose(1, 2, 0)] * n).astype(np.float32)
    return {"motion": motion, "text": ["a person walks"] * n, "lengths": np.full(n, t), "num_samples": n,
            "num_repetitions": 1}


def robot_npz(d: Path, name: str = "r.npz", *, fps: object = 50.0, frames: int = 20, qpos: np.ndarray | None = None,
              names: object = None, robot: str = "op3", meta: str = "{}") -> Path:
    from motion2robot.robot import load_robot

    r = load_robot("op3")
    q = np.tile(r.nominal_qpos, (frames, 1)) if qpos is None else qpos
    p = d / name
    np.savez(p, qpos=q, fps=np.asarray(fps), joint_names=np.array(r.joint_names if names is None else names),
             robot=np.array(robot), meta=np.array(meta))
    return p


def good_robot_npz(d: Path) -> Path:
    return robot_npz(d, "good.npz")


def text(d: Path, name: str, body: str | bytes) -> Path:
    p = d / name
    if isinstance(body, bytes):
        p.write_bytes(body)
    else:
        p.write_text(body)
    return p


def bvh(d: Path, body: str, name: str = "m.bvh") -> Path:
    return text(d, name, body)


def robot_toml(d: Path, edit: Callable[[str], str]) -> Path:
    src = OP3_TOML.read_text().replace('mjcf = "op3.xml"', f'mjcf = "{OP3_TOML.parent / "op3.xml"}"')
    out = edit(src)
    assert out != src, "the edit changed nothing"
    return text(d, "bot.toml", out)


def inspect(p: Path, *extra: str) -> list[str]:
    return ["inspect", str(p), *extra]


GOOD_BVH = bvh_text()
J = walking_yup(30)  # a valid (T, 22, 3) HumanML3D clip
STREAM = ["--dry-run", "--telemetry"]



def _register() -> None:
    """Import the case modules (each case registers itself in CASES)."""
    from tests.fuzz import cases_commands, cases_files  # noqa: F401


_register()

"""Robot motion: what the retargeter produces, the checks judge and the streamer plays.

``qpos`` is (T, nq) in MuJoCo order for the robot's model: free root position xyz (metres, world
frame, z up), root quaternion **wxyz**, then the hinge angles (radians) in model order
(``joint_names``). Saved as ``.npz`` with exactly the keys ``qpos``, ``fps``, ``joint_names``,
``robot``, ``meta`` (a JSON string).
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from motion2robot.errors import InputFileError
from motion2robot.util.files import UNREADABLE_FIX, special_file, unreadable
from motion2robot.util.frames import Frames
from motion2robot.util.jsonable import plain

NPZ_KEYS = ("qpos", "fps", "joint_names", "robot", "meta")


@dataclass(frozen=True, eq=False)
class RobotMotion(Frames):
    """A joint-space trajectory of one robot.

    qpos: (T, 7 + n) float64: root xyz (m), root quaternion wxyz, n hinge angles (rad).
    fps: frames per second.
    joint_names: the n hinge names in model order.
    robot: the robot's name as resolved (``op3``, ``menagerie:unitree_g1``, a path), and
        ``meta["robot_hash"]`` the model hash it was made for.
    meta: JSON-serialisable facts: source file, clip, prompt, scale, solver figures, ...
    """

    qpos: np.ndarray
    fps: float
    joint_names: tuple[str, ...]
    robot: str
    meta: Mapping[str, Any] = field(default_factory=dict)

    _frames_field = "qpos"  # not a field (no annotation): the array whose rows are the frames

    def __post_init__(self) -> None:
        q = np.array(self.qpos, dtype=np.float64)
        names = tuple(str(n) for n in self.joint_names)
        if q.ndim != 2 or q.shape[1] != 7 + len(names):
            raise ValueError(f"qpos must be (T, 7 + {len(names)}), got {q.shape}")
        q.flags.writeable = False
        object.__setattr__(self, "qpos", q)
        object.__setattr__(self, "joint_names", names)
        self._freeze_rate_and_meta()

    @property
    def root_pos(self) -> np.ndarray:
        """(T, 3) root position, metres."""
        return self.qpos[:, :3]

    @property
    def root_quat(self) -> np.ndarray:
        """(T, 4) root orientation, wxyz."""
        return self.qpos[:, 3:7]

    @property
    def joints(self) -> np.ndarray:
        """(T, n) hinge angles, radians, in ``joint_names`` order."""
        return self.qpos[:, 7:]

    def save(self, path: str | Path) -> Path:
        """Write the ``.npz`` with exactly the keys of :data:`NPZ_KEYS`; returns the path."""
        path = Path(path)
        if not np.all(np.isfinite(self.qpos)) or not (np.isfinite(self.fps) and self.fps > 0):
            bad = np.where(~np.all(np.isfinite(self.qpos), axis=1))[0]  # a bug upstream: never write it
            raise ValueError(f"refusing to write {path}: qpos has NaN/inf in frames {_ranges(bad)} or fps is {self.fps}")
        if path.is_dir():
            raise InputFileError(f"{path}: is a directory; give a file name for the robot motion, e.g. {path / 'out.npz'}")
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise InputFileError(f"{path}: cannot create its folder ({err.strerror}); choose another output path") from None
        tmp = path.with_name(path.name + ".part.npz")
        try:
            np.savez(
                tmp,
                qpos=self.qpos,
                fps=np.float64(self.fps),
                joint_names=np.array(self.joint_names, dtype=str),
                robot=np.array(self.robot, dtype=str),
                meta=np.array(json.dumps(plain(self.meta)), dtype=str),
            )
            tmp.replace(path)
        except PermissionError:
            tmp.unlink(missing_ok=True)
            raise InputFileError(f"{path}: cannot be written (permission denied); choose another output path, "
                                 "or fix the permissions of its folder") from None
        return path

    @classmethod
    def load(cls, path: str | Path) -> "RobotMotion":
        """Read a RobotMotion ``.npz`` (no pickle); bad files raise :class:`InputFileError`."""
        path = Path(path)
        if path.is_dir():
            raise InputFileError(f"{path}: is a directory, not a robot motion .npz; give the file made by 'motion2robot retarget'")
        if not path.exists():
            raise InputFileError(f"{path}: no such file; check the path")
        special = special_file(path)
        if special is not None:  # a FIFO would block np.load for ever
            raise InputFileError(f"{path}: {special}, not a robot motion .npz; give the file made by 'motion2robot retarget'")
        denied = unreadable(path)
        if denied is not None:
            raise InputFileError(f"{path}: {denied}; {UNREADABLE_FIX}")
        from motion2robot.motion.archive import read_npz_members

        try:
            if not zipfile.is_zipfile(path):
                with open(path, "rb") as fh:
                    if fh.read(6) == b"\x93NUMPY":
                        raise InputFileError(f"{path}: is a single array (.npy), not a robot motion .npz; human "
                                             "motion must be retargeted first: 'motion2robot retarget'")
                raise InputFileError(f"{path}: is not an .npz archive; give the file made by 'motion2robot retarget'")
            z = read_npz_members(path, NPZ_KEYS)  # capped, no pickle
            missing = [k for k in NPZ_KEYS if k not in z]
            if missing:
                raise InputFileError(
                    f"{path}: not a robot motion (missing {', '.join(missing)}); "
                    "make one with 'motion2robot retarget'")
            qpos = np.asarray(z["qpos"], dtype=np.float64)
            fps = float(z["fps"])
            names = tuple(str(n) for n in z["joint_names"].tolist())
            robot = str(z["robot"])
            meta = json.loads(str(z["meta"]))
        except InputFileError:
            raise
        except (OSError, ValueError, TypeError, EOFError, zipfile.BadZipFile, json.JSONDecodeError, KeyError) as err:
            raise InputFileError(
                f"{path}: cannot read as a robot motion .npz ({err}); make one with 'motion2robot retarget'"
            ) from err
        if qpos.ndim != 2 or qpos.shape[1] != 7 + len(names):
            raise InputFileError(f"{path}: qpos has shape {qpos.shape} but {len(names)} joint names; the file is damaged, retarget again")
        if not np.all(np.isfinite(qpos)):
            bad = np.where(~np.all(np.isfinite(qpos), axis=1))[0]
            raise InputFileError(f"{path}: qpos has NaN/inf in frames {_ranges(bad)}; retarget again")
        if qpos.shape[0] < 1:
            raise InputFileError(f"{path}: holds 0 frames; retarget a clip with frames")
        if not (np.isfinite(fps) and 0.1 <= fps <= 10000):
            raise InputFileError(f"{path}: fps is {fps}, not a frame rate (0.1 to 10000); the file is damaged, "
                                 "retarget again")
        return cls(qpos=qpos, fps=fps, joint_names=names, robot=robot, meta=meta)


def _ranges(idx: np.ndarray, limit: int = 6) -> str:
    """'3-7, 12, 20-21' for sorted frame indices."""
    from motion2robot.util.ranges import frame_ranges

    return frame_ranges(idx, limit)

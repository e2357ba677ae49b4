"""What format detectors look at: a file's suffix, first bytes, .npy header and zip members.

Each fact is read once, on first use, so a detector that only needs the suffix costs no I/O.
"""

from __future__ import annotations

import zipfile
from functools import cached_property
from pathlib import Path

import numpy as np

from motion2robot.motion.checks import fail
from motion2robot.motion.safe_pickle import read_npy_header


class Probe:
    """Lazily read facts about one existing, non-empty file."""

    def __init__(self, path: Path, npy_header: tuple[tuple[int, ...], np.dtype] | None = None):
        """npy_header: (shape, dtype) already parsed by the caller (the file is then a .npy)."""
        self.path = path
        self.suffix = path.suffix.lower()
        if npy_header is not None:
            self.__dict__["head"] = b"\x93NUMPY"
            self.__dict__["_npy_header"] = npy_header

    @cached_property
    def head(self) -> bytes:
        with open(self.path, "rb") as fh:
            return fh.read(64)

    @property
    def is_npy(self) -> bool:
        return self.head.startswith(b"\x93NUMPY")

    @property
    def is_zip(self) -> bool:
        return self.head.startswith(b"PK")

    def text_starts(self, word: str) -> bool:
        return self.head.lstrip().startswith(word.encode())

    @cached_property
    def _npy_header(self) -> tuple[tuple[int, ...], np.dtype]:
        with open(self.path, "rb") as fh:
            header = read_npy_header(self.path, fh)
        return header.shape, header.dtype

    @property
    def npy_shape(self) -> tuple[int, ...]:
        return self._npy_header[0]

    @property
    def npy_dtype(self) -> np.dtype:
        return self._npy_header[1]

    @cached_property
    def npy_object_keys(self) -> frozenset[str]:
        """Keys of the dict an object .npy holds (restricted unpickler), else empty."""
        from motion2robot.motion.safe_pickle import load_npy

        obj = load_npy(self.path)
        return frozenset(map(str, obj)) if isinstance(obj, dict) else frozenset()

    @cached_property
    def zip_names(self) -> tuple[str, ...]:
        try:
            with zipfile.ZipFile(self.path) as z:
                return tuple(z.namelist())
        except zipfile.BadZipFile:
            raise fail(self.path, "is a damaged zip/.npz file", "re-export the file") from None

    def zip_has_suffix(self, ending: str) -> bool:
        return any(n.endswith(ending) for n in self.zip_names)

    @property
    def npz_keys(self) -> set[str]:
        """Array names of an .npz (its members ending in .npy, without that ending)."""
        return {n[:-4] for n in self.zip_names if n.endswith(".npy")}

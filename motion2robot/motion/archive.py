"""Reading arrays out of .npz archives without trusting them: no pickle, members capped in
their expanded size before they are decompressed, headers promising more data than the member
holds refused before anything is allocated, damaged archives (bad CRC, truncated members, members
that are not arrays) reported as one-line input errors. Every .npz a user hands over (joints,
AMASS parameters, body models, robot motions, batch counts) is read here."""

from __future__ import annotations

import math
import tokenize
import zipfile
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import IO

import numpy as np
from numpy.lib import format as npformat

from motion2robot.motion.checks import fail

#: Largest expanded size of one .npz member read as motion data (bytes): 256 MiB is 508,000 frames of
#: 22 float64 joints (70 min at 120 fps, 7 h at 20 fps), far beyond any clip; a small archive that
#: expands past it is refused before it is decompressed (issue 20: a 2.3 MB file expanding to 528 MB
#: took 17 s and 3.5 GB; 528 MB is above this cap).
MAX_MEMBER_BYTES = 256 * 1024 * 1024
_SAVE_FIX = "save plain numeric arrays with numpy.savez"


class NpzMembers(Mapping[str, np.ndarray]):
    """The requested members of an archive as arrays; ``names`` lists every member found."""

    def __init__(self, arrays: dict[str, np.ndarray], names: list[str]):
        self._arrays = arrays
        self.names = names

    def __getitem__(self, key: str) -> np.ndarray:
        return self._arrays[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._arrays)

    def __len__(self) -> int:
        return len(self._arrays)


def _header(path: Path, info: zipfile.ZipInfo, fh: IO[bytes]) -> tuple[tuple[int, ...], bool, np.dtype, int]:
    """Shape, Fortran order, dtype and byte count of a member's .npy header, checked against the
    member's size: nothing is allocated for data the member does not hold."""
    try:
        version = npformat.read_magic(fh)
        if version not in ((1, 0), (2, 0)):
            raise ValueError(f"unsupported .npy version {version}")
        read = npformat.read_array_header_1_0 if version == (1, 0) else npformat.read_array_header_2_0
        shape, fortran, dtype = read(fh)
    except (ValueError, SyntaxError, tokenize.TokenError) as err:
        raise fail(path, f"member {info.filename} is not a readable array ({err})", _SAVE_FIX) from None
    if dtype.hasobject:
        raise fail(path, "holds object arrays (pickled Python objects), which are not read from .npz files for "
                         "safety", _SAVE_FIX)
    if not all(isinstance(n, int) and n >= 0 for n in shape):
        raise fail(path, f"member {info.filename} has a broken header (shape {tuple(shape)})", _SAVE_FIX)
    nbytes = math.prod(shape) * dtype.itemsize
    held = info.file_size - fh.tell()
    if nbytes > held:
        raise fail(path, f"member {info.filename} is damaged: its header promises {tuple(shape)} {dtype} = "
                         f"{nbytes} bytes, it holds {held}", "re-export or re-download the file")
    return tuple(shape), bool(fortran), dtype, nbytes


def _array(path: Path, z: zipfile.ZipFile, info: zipfile.ZipInfo, max_bytes: int) -> np.ndarray:
    if info.file_size > max_bytes:
        raise fail(path, f"member {info.filename} expands to {info.file_size / 1e6:.0f} MB, above the "
                         f"{max_bytes / 1e6:.0f} MB allowed for one motion array", "split the motion into smaller files")
    with z.open(info) as fh:
        shape, fortran, dtype, nbytes = _header(path, info, fh)
        buf = bytearray(nbytes)
        if fh.readinto(buf) != nbytes:
            raise fail(path, f"member {info.filename} is truncated", "re-export or re-download the file")
    arr = np.frombuffer(buf, dtype=dtype, count=math.prod(shape))
    return arr.reshape(shape[::-1]).transpose() if fortran else arr.reshape(shape)


@contextmanager
def _archive(path: Path) -> Iterator[dict[str, tuple[zipfile.ZipFile, zipfile.ZipInfo]]]:
    """The archive's .npy members by name (without ``.npy``); damage is a one-line input error."""
    try:
        with zipfile.ZipFile(path) as z:
            yield {i.filename[:-4]: (z, i) for i in z.infolist() if i.filename.endswith(".npy")}
    except zipfile.BadZipFile as err:  # also a bad CRC, found when a member is read
        raise fail(path, f"is a damaged .npz archive ({err})", "re-export or re-download the file") from None
    except (OSError, EOFError) as err:
        raise fail(path, f"cannot be read as an .npz archive ({err})", "re-export or re-download the file") from None


def read_npz_members(path: str | Path, wanted: Iterable[str], max_bytes: int | None = None) -> NpzMembers:
    """Read the members ``wanted`` (names without ``.npy``) of the .npz at ``path``, each at most
    ``max_bytes`` expanded (default :data:`MAX_MEMBER_BYTES`), without pickle."""
    path = Path(path)
    cap = MAX_MEMBER_BYTES if max_bytes is None else max_bytes
    with _archive(path) as members:
        out = {name: _array(path, *members[name], cap) for name in wanted if name in members}
        return NpzMembers(out, sorted(members))


def npz_member_shape(path: str | Path, name: str) -> tuple[int, ...] | None:
    """Shape of the member ``name`` from its header alone (None if absent): nothing decompressed
    beyond the header, a header promising more than the member holds refused."""
    path = Path(path)
    with _archive(path) as members:
        if name not in members:
            return None
        z, info = members[name]
        with z.open(info) as fh:
            return _header(path, info, fh)[0]

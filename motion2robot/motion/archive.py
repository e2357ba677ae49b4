"""Reading arrays out of .npz archives without trusting them: no pickle, members capped in
their expanded size before they are decompressed, damaged archives (bad CRC, truncated members,
members that are not arrays) reported as one-line input errors."""

from __future__ import annotations

import zipfile
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path

import numpy as np

from motion2robot.motion.checks import fail

#: Largest expanded size of one .npz member read as motion data (bytes): 512 MB is 2 million frames
#: of 22 float64 joints, far beyond any clip; a small archive that expands past it is refused
#: before it is decompressed (a 2.3 MB file expanding to 528 MB took 17 s and 3.5 GB).
MAX_MEMBER_BYTES = 512 * 1024 * 1024


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


def read_npz_members(path: str | Path, wanted: Iterable[str], max_bytes: int = MAX_MEMBER_BYTES) -> NpzMembers:
    """Read the members ``wanted`` (names without ``.npy``) of the .npz at ``path``."""
    path = Path(path)
    try:
        with zipfile.ZipFile(path) as z:
            infos = {i.filename[:-4]: i for i in z.infolist() if i.filename.endswith(".npy")}
            out: dict[str, np.ndarray] = {}
            for name in wanted:
                info = infos.get(name)
                if info is None:
                    continue
                if info.file_size > max_bytes:
                    raise fail(path, f"member {info.filename} expands to {info.file_size / 1e6:.0f} MB, above the "
                                     f"{max_bytes / 1e6:.0f} MB allowed for one motion array",
                               "split the motion into smaller files")
                with z.open(info) as fh:
                    try:
                        arr = np.lib.format.read_array(fh, allow_pickle=False)
                    except ValueError as err:
                        what = ("holds object arrays (pickled Python objects), which are not read from .npz files "
                                "for safety" if "allow_pickle" in str(err) else f"member {info.filename} is not a "
                                f"readable array ({err})")
                        raise fail(path, what, "save plain numeric arrays with numpy.savez") from None
                out[name] = arr
            return NpzMembers(out, sorted(infos))
    except zipfile.BadZipFile as err:
        raise fail(path, f"is a damaged .npz archive ({err})", "re-export or re-download the file") from None
    except (OSError, EOFError) as err:
        raise fail(path, f"cannot be read as an .npz archive ({err})", "re-export or re-download the file") from None

"""Loading .npy / pickle files without letting them run code.

numpy stores object arrays (e.g. MDM's ``results.npy`` dict) as a pickle after the .npy header.
:class:`RestrictedUnpickler` admits only the globals needed to rebuild numpy arrays, dtypes and
scalars and plain containers; any other global (os.system, eval, a class of some package...) is
refused with an :class:`~motion2robot.errors.InputFileError` before it is looked up.
"""

from __future__ import annotations

import collections
import io
import math
import os
import pickle
import re
import tokenize
from pathlib import Path
from typing import Any, BinaryIO, NamedTuple

import numpy as np
from numpy.lib import format as npformat

from motion2robot.motion.checks import fail

try:  # numpy >= 2
    from numpy._core import multiarray as _multiarray
    from numpy._core import numeric as _numeric
except ImportError:  # pragma: no cover - numpy 1.x
    from numpy.core import multiarray as _multiarray  # type: ignore[no-redef]
    from numpy.core import numeric as _numeric  # type: ignore[no-redef]

_NUMPY_GLOBALS: dict[str, Any] = {
    "_reconstruct": _multiarray._reconstruct,
    "scalar": _multiarray.scalar,
    "_frombuffer": getattr(_numeric, "_frombuffer", None),
}
_ALLOWED: dict[tuple[str, str], Any] = {
    ("numpy", "ndarray"): np.ndarray,
    ("numpy", "dtype"): np.dtype,
    ("collections", "OrderedDict"): collections.OrderedDict,
    ("_codecs", "encode"): __import__("codecs").encode,  # protocol-2 bytes: encode(str, 'latin1')
}
for _mod in ("numpy.core.multiarray", "numpy._core.multiarray", "numpy.core.numeric", "numpy._core.numeric"):
    for _name, _obj in _NUMPY_GLOBALS.items():
        if _obj is not None:
            _ALLOWED[(_mod, _name)] = _obj
for _mod in ("builtins", "__builtin__"):
    for _t in (dict, list, tuple, set, frozenset, bytearray, complex):
        _ALLOWED[(_mod, _t.__name__)] = _t
for _mod in ("numpy", "numpy.core.numerictypes", "numpy._core.numerictypes"):  # scalar dtypes by name
    for _t in (np.float16, np.float32, np.float64, np.int8, np.int16, np.int32, np.int64,
               np.uint8, np.uint16, np.uint32, np.uint64, np.bool_, np.str_, np.bytes_):
        _ALLOWED[(_mod, _t.__name__)] = _t
for _mod in ("numpy.dtypes",):  # numpy 2 pickles dtypes by their class
    for _n in ("Float32DType", "Float64DType", "Int64DType", "Int32DType", "BoolDType", "StrDType",
               "ObjectDType", "Float16DType", "UInt8DType"):
        if hasattr(np.dtypes, _n):
            _ALLOWED[(_mod, _n)] = getattr(np.dtypes, _n)


class RestrictedUnpickler(pickle.Unpickler):
    """Unpickler that admits only numpy array reconstruction and plain containers."""

    def __init__(self, file: Any, path: str | Path = "<pickle>"):
        super().__init__(file, encoding="latin1")
        self._path = path

    def find_class(self, module: str, name: str) -> Any:
        obj = _ALLOWED.get((module, name))
        if obj is None:
            raise fail(self._path, f"refused: the file's pickle asks for {module}.{name}, which could "
                                   "run code (only numpy arrays and plain containers are allowed)",
                       "re-save the data with plain numpy arrays, or load it yourself if you trust it")
        return obj

    def persistent_load(self, pid: Any) -> Any:
        raise fail(self._path, "refused: the pickle uses persistent ids", "re-save it as plain numpy data")


def restricted_load(path: str | Path, fh: Any) -> Any:
    """Unpickle from an open binary file with :class:`RestrictedUnpickler`."""
    try:
        return RestrictedUnpickler(fh, path).load()
    except (pickle.UnpicklingError, EOFError, ValueError, TypeError, AttributeError,
            IndexError, KeyError, MemoryError, UnicodeDecodeError) as err:
        raise fail(path, f"is not a readable pickle ({type(err).__name__}: {err})",
                   "check the file is complete and was saved with numpy/pickle") from None


class NpyHeader(NamedTuple):
    """What a .npy header says: array shape, Fortran order, dtype, and where the data starts."""

    shape: tuple[int, ...]
    fortran_order: bool
    dtype: np.dtype
    data_offset: int


#: The header dict exactly as numpy.save writes it; anything else goes through numpy's parser.
_HEADER_RE = re.compile(r"\{'descr': '([^']+)', 'fortran_order': (True|False), 'shape': \(([0-9, ]*)\), \} *\n?")
_MAGIC = b"\x93NUMPY"


def _fast_header(text: str) -> tuple[tuple[int, ...], bool, np.dtype] | None:
    m = _HEADER_RE.fullmatch(text)
    if m is None:
        return None
    try:
        shape = tuple(int(s) for s in m.group(3).split(",") if s.strip())
        dtype = np.dtype(m.group(1))
    except (TypeError, ValueError):
        return None
    if m.group(3).strip() and len(shape) == 1 and not m.group(3).rstrip().endswith(","):
        return None  # "(5)" is not a tuple: let numpy's parser refuse it
    return shape, m.group(2) == "True", dtype


def read_npy_header(path: str | Path, fh: BinaryIO) -> NpyHeader:
    """Parse the .npy header of an open binary file positioned at its start, leaving the file at
    the first data byte. The header is parsed once; numpy.save's own layout takes a fast path,
    any other valid header goes through numpy's parser. Raises InputFileError on a bad header."""
    lead = fh.read(12)
    if lead[:6] != _MAGIC:
        if not lead:
            raise fail(path, "is empty (0 bytes)", "re-export or re-download the file")
        raise fail(path, "is not a numpy .npy file (no NUMPY magic bytes)",
                   "give a .npy saved with numpy.save, or pass --format")
    version = (lead[6], lead[7]) if len(lead) >= 8 else None
    if version == (1, 0) and len(lead) >= 10:
        hlen, start = int.from_bytes(lead[8:10], "little"), 10
    elif version == (2, 0) and len(lead) >= 12:
        hlen, start = int.from_bytes(lead[8:12], "little"), 12
    else:
        hlen = start = -1
    parsed = None
    if hlen >= 0:
        raw = lead[start:] + fh.read(hlen - (len(lead) - start))
        if len(raw) == hlen:
            try:
                parsed = _fast_header(raw.decode("latin1"))
            except UnicodeDecodeError:  # pragma: no cover - latin1 decodes any byte
                parsed = None
    if parsed is not None:
        return NpyHeader(*parsed, start + hlen)
    fh.seek(0)
    try:
        version = npformat.read_magic(fh)
        if version == (1, 0):
            shape, fortran, dtype = npformat.read_array_header_1_0(fh)
        elif version == (2, 0):
            shape, fortran, dtype = npformat.read_array_header_2_0(fh)
        else:
            raise ValueError(f"unsupported .npy version {version}")
    except (ValueError, SyntaxError, tokenize.TokenError) as err:
        raise fail(path, f"has a broken .npy header ({err})", "re-export the file") from None
    if not all(isinstance(n, int) and n >= 0 for n in shape):
        raise fail(path, f"has a broken .npy header (shape {tuple(shape)} has negative sizes)", "re-export the file")
    return NpyHeader(tuple(shape), bool(fortran), dtype, fh.tell())


def read_npy_data(path: str | Path, fh: BinaryIO, header: NpyHeader) -> Any:
    """The content after :func:`read_npy_header`: a writable numeric ndarray, or for object arrays
    the restricted-unpickled content (a 0-d object array becomes its item, e.g. MDM's dict)."""
    if header.dtype.hasobject:
        obj = restricted_load(path, fh)
        if isinstance(obj, np.ndarray) and obj.dtype.hasobject and obj.shape == ():
            return obj.item()
        return obj
    shape = header.shape
    count = math.prod(shape)
    nbytes = count * header.dtype.itemsize
    try:  # a truncated file or a header claiming a huge shape: refuse before allocating
        avail = os.fstat(fh.fileno()).st_size - fh.tell()
    except (AttributeError, OSError, io.UnsupportedOperation):
        avail = nbytes
    buf = bytearray(nbytes if avail >= nbytes else 0)
    got = fh.readinto(buf) if len(buf) else 0
    if got != nbytes:
        raise fail(path, f"is a damaged .npy file (truncated: its header promises {shape} {header.dtype} = "
                         f"{nbytes} bytes of data, the file holds {got if len(buf) else avail})",
                   "re-export or re-download it")
    try:
        arr = np.frombuffer(buf, dtype=header.dtype, count=count)
    except ValueError as err:  # e.g. a zero-size dtype
        raise fail(path, f"is a damaged .npy file ({err})", "re-export or re-download it") from None
    if header.fortran_order:
        return arr.reshape(shape[::-1]).transpose()
    return arr.reshape(shape)


def load_npy(path: str | Path) -> Any:
    """Read a .npy file: a numeric ndarray, or for object arrays the restricted-unpickled content
    (a 0-d object array becomes its item, e.g. MDM's dict)."""
    path = Path(path)
    with open(path, "rb") as fh:
        return read_npy_data(path, fh, read_npy_header(path, fh))

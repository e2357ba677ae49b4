"""C loops that call MuJoCo directly: built against the headers and the library the ``mujoco``
package ships, on the Python bindings' own ``MjModel``/``MjData`` (their ``_address``).

Frame loops of a few MuJoCo calls each spend most of their time in Python between the calls; the
same calls in C give the same numbers (the same functions, the same order of operations; no
floating-point contraction). A kernel is compiled on first use and cached in
``$MOTION2ROBOT_CACHE/native`` under a digest of its source, the flags and the MuJoCo version.
Without a C compiler, without the headers or the library in the package, or with
``MOTION2ROBOT_NATIVE=0``, :func:`load` returns None and the callers run their Python loops.
"""

from __future__ import annotations

import ctypes
import functools
from pathlib import Path

import mujoco

#: No floating-point contraction (FMA): the numbers are the Python loops'.
FLAGS = ("-ffp-contract=off",)


def _package() -> Path:
    return Path(mujoco.__file__).parent


def _library() -> Path | None:
    libs = sorted(_package().glob("libmujoco.so*")) + sorted(_package().glob("libmujoco*.dylib"))
    return libs[0] if libs else None


@functools.lru_cache(maxsize=None)
def load(name: str, source: str) -> ctypes.CDLL | None:
    """The kernel ``name`` compiled from C ``source`` (which includes ``<mujoco/mujoco.h>``),
    loaded; None when it cannot be built here (module text)."""
    from motion2robot.retarget.compiled import cached_library

    lib, include = _library(), _package() / "include"
    if lib is None or not (include / "mujoco" / "mujoco.h").is_file():
        return None
    return cached_library(name, source, (*FLAGS, f"-I{include}", str(lib), f"-Wl,-rpath,{lib.parent}"),
                          salt=mujoco.__version__)


def address(a) -> int | None:
    """The data address of a C-contiguous numpy array (None for None), for ``void *`` arguments."""
    return None if a is None else a.ctypes.data

"""Freed heap memory handed back to the operating system in long-running workers.

A batch worker retargets thousands of clips of slightly different lengths; the native libraries
(casadi, OSQP, MuJoCo) free what each clip allocated, but glibc keeps the freed pages for reuse,
so a worker's resident memory grows in a sawtooth (measured on op3: 101 -> 360 MB over 3,000
clips, dropping back to ~125 MB whenever glibc consolidates) although what it holds stays flat
(about 105 MB after ``malloc_trim``). Trimming every :data:`EVERY` clips keeps the resident figure
at what is in use. Elsewhere than glibc (macOS, musl) this is a no-op.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools

#: Clips between two trims (each trim costs well under a millisecond when little is free).
EVERY = 20


@functools.lru_cache(maxsize=1)
def _malloc_trim():
    """glibc's ``malloc_trim`` or None where the C library has none."""
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        fn = libc.malloc_trim
    except (OSError, AttributeError):
        return None
    fn.argtypes, fn.restype = [ctypes.c_size_t], ctypes.c_int
    return fn


class _Counter:
    calls = 0


def trim_now() -> bool:
    """Hand freed heap pages back to the OS now; True where that is possible (glibc)."""
    fn = _malloc_trim()
    if fn is None:
        return False
    fn(0)
    return True


def after_clip() -> None:
    """Count one clip done; every :data:`EVERY` clips, :func:`trim_now`."""
    _Counter.calls += 1
    if _Counter.calls % EVERY == 0:
        trim_now()

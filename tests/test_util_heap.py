"""Freed heap handed back to the OS every EVERY clips in batch workers."""

from __future__ import annotations

import sys

import pytest

from motion2robot.util import heap


def test_after_clip_trims_every_n_clips(monkeypatch) -> None:
    trims = []
    monkeypatch.setattr(heap, "trim_now", lambda: trims.append(1) or True)
    monkeypatch.setattr(heap._Counter, "calls", 0)
    for _ in range(3 * heap.EVERY + 1):
        heap.after_clip()
    assert len(trims) == 3


#: Run in a fresh interpreter: in the test process the heap's layout depends on every test before.
_MEASURE = """
import json, numpy as np
from motion2robot.util import heap

def rss_mb():
    return int(open("/proc/self/status").read().split("VmRSS:")[1].split()[0]) / 1024

start = rss_mb()
blocks = [np.ones(500) for _ in range(25_000)]  # 4 kB each, below glibc's mmap threshold: heap pages
pin = np.ones(500)  # allocated last: the heap's top stays in use, so free() alone returns nothing
grown = rss_mb() - start
del blocks
kept = rss_mb() - start  # freed, still resident
trimmed = heap.trim_now()
print(json.dumps([grown, kept, rss_mb() - start, trimmed]))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux") or heap._malloc_trim() is None, reason="glibc's malloc_trim")
def test_trim_gives_freed_pages_back_on_glibc() -> None:
    import json
    import subprocess

    out = subprocess.run([sys.executable, "-c", _MEASURE], capture_output=True, text=True, check=True, timeout=120)
    grown, kept, after, trimmed = json.loads(out.stdout.strip().splitlines()[-1])
    assert trimmed is True
    assert grown > 80 and kept > 0.8 * grown and after < 0.3 * grown, (grown, kept, after)

"""Turning index sets into the short text used in messages ("frames 40-52, 60")."""

from __future__ import annotations

from typing import Iterable

import numpy as np


def runs(idx: Iterable[int]) -> list[tuple[int, int]]:
    """Contiguous runs [(first, last), ...] of sorted unique integer indices."""
    a = np.unique(np.asarray(list(idx), dtype=np.int64))
    if a.size == 0:
        return []
    breaks = np.where(np.diff(a) != 1)[0]
    starts = np.concatenate([[a[0]], a[breaks + 1]])
    ends = np.concatenate([a[breaks], [a[-1]]])
    return [(int(s), int(e)) for s, e in zip(starts, ends)]


def frame_ranges(idx: Iterable[int], limit: int = 6) -> str:
    """'3-7, 12, 20-21' (at most ``limit`` runs, then '... (N runs)')."""
    r = runs(idx)
    parts = [f"{s}-{e}" if e > s else f"{s}" for s, e in r[:limit]]
    if len(r) > limit:
        parts.append(f"... ({len(r)} runs)")
    return ", ".join(parts)

"""Generators' output folders that hold one motion several times: keep one file per motion.

MoMask writes every generated sample four times: ``joints/<k>/sample{k}_repeat{r}_len{L}.npy``, the
foot-IK-cleaned ``..._ik.npy``, and the same two as BVH under ``animations/<k>/``. A batch over its
output folder keeps the foot-IK-cleaned joints (cleaner contacts for the robot) and lists the others
as skipped, so each sample is retargeted and counted once.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Iterable

_MOMASK = re.compile(r"^sample(\d+)_repeat(\d+)_len(\d+)(_ik)?\.(npy|bvh)$", re.IGNORECASE)
#: Preference among a sample's copies: (folder, IK-cleaned, extension) -> rank (lower is kept).
_RANK = {("joints", True): 0, ("joints", False): 1, ("animations", True): 2, ("animations", False): 3}


def momask_key(path: Path) -> tuple[tuple, int] | None:
    """(identity of the sample, preference rank) of a file in a MoMask output folder, else None."""
    m = _MOMASK.match(path.name)
    kind = path.parent.parent.name.lower() if len(path.parts) > 2 else ""
    if m is None or kind not in ("joints", "animations") or (kind == "joints") != (m.group(5).lower() == "npy"):
        return None
    root = path.parent.parent.parent
    return (str(root), path.parent.name, m.group(1), m.group(2), m.group(3)), _RANK[(kind, bool(m.group(4)))]


def duplicate_outputs(files: Iterable[Path]) -> dict[Path, str]:
    """{file: why it is skipped} for the extra copies of each generated motion among ``files``."""
    best: dict[tuple, tuple[int, Path]] = {}
    keyed: list[tuple[Path, tuple]] = []
    for f in files:
        k = momask_key(f)
        if k is None:
            continue
        keyed.append((f, k[0]))
        if k[0] not in best or k[1] < best[k[0]][0]:
            best[k[0]] = (k[1], f)
    out = {}
    for f, key in keyed:
        kept = best[key][1]
        if f != kept:
            rel = Path(kept.parent.parent.name, kept.parent.name, kept.name)
            out[f] = f"MoMask copy of the motion in {rel} (that one is processed)"
    return out

"""Where motion2robot keeps what it builds once per machine (compiled problem code, joint-space
collision cuts): ``$MOTION2ROBOT_CACHE`` or ``~/.cache/motion2robot``."""

from __future__ import annotations

import os
from pathlib import Path


def cache_dir() -> Path:
    root = os.environ.get("MOTION2ROBOT_CACHE")
    return Path(root) if root else Path.home() / ".cache" / "motion2robot"


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` via a temporary file and a rename (readers never see half a
    file); a cache that cannot be written is skipped silently (the next process rebuilds)."""
    part = path.with_name(path.name + f".{os.getpid()}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        part.write_text(text)
        part.replace(path)
    except OSError:
        pass

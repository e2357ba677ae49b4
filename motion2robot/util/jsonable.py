"""Turning results (numpy arrays and scalars, paths, tuples, sets) into plain JSON values."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np


def plain(obj: Any, *, fallback_str: bool = False) -> Any:
    """A JSON-safe copy of ``obj``: numpy arrays/scalars become lists/numbers, paths strings,
    tuples and sets lists, dict keys strings, NaN/inf ``None``. Anything else raises TypeError,
    or becomes ``str(obj)`` with ``fallback_str``."""
    if isinstance(obj, dict):
        return {str(k): plain(v, fallback_str=fallback_str) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [plain(v, fallback_str=fallback_str) for v in obj]
    if isinstance(obj, np.ndarray):
        return plain(obj.tolist(), fallback_str=fallback_str)
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else None
    if obj is None or isinstance(obj, str):
        return obj
    if isinstance(obj, Path):
        return str(obj)
    if hasattr(obj, "items"):  # mappingproxy and other read-only mappings
        return plain(dict(obj.items()), fallback_str=fallback_str)
    if fallback_str:
        return str(obj)
    raise TypeError(f"not JSON-serialisable: {type(obj).__name__}")

"""What a human motion and a robot motion share: T frames at ``fps`` frames per second, facts in a
read-only ``meta``, copies with fields replaced, and pickling for worker processes."""

from __future__ import annotations

from dataclasses import fields, replace
from types import MappingProxyType
from typing import Any, ClassVar, Self


class Frames:
    """Mixin for a frozen dataclass with fields ``fps`` and ``meta`` and one (T, ...) array whose
    name is ``_frames_field``."""

    _frames_field: ClassVar[str]

    def _freeze_rate_and_meta(self) -> None:
        """``fps`` as a float, ``meta`` as a read-only copy (call from ``__post_init__``)."""
        object.__setattr__(self, "fps", float(self.fps))  # type: ignore[attr-defined]
        object.__setattr__(self, "meta", MappingProxyType(dict(self.meta)))  # type: ignore[attr-defined]

    def __reduce__(self) -> tuple:
        """Pickle support (worker processes): the fields in order, ``meta`` as a plain dict."""
        return type(self), tuple(dict(v) if isinstance(v, MappingProxyType) else v
                                 for v in (getattr(self, f.name) for f in fields(self)))  # type: ignore[arg-type]

    @property
    def num_frames(self) -> int:
        return int(getattr(self, self._frames_field).shape[0])

    @property
    def duration(self) -> float:
        """Seconds: the number of frames times the frame period (the last frame lasts one period)."""
        return self.num_frames / self.fps  # type: ignore[attr-defined]

    def with_(self, **changes: Any) -> Self:
        """A copy with some fields replaced (``meta`` is merged, not replaced)."""
        if "meta" in changes:
            changes["meta"] = {**self.meta, **changes["meta"]}  # type: ignore[attr-defined]
        return replace(self, **changes)  # type: ignore[type-var]

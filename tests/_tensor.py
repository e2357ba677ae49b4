"""A duck-typed torch tensor for the tests (torch is never imported by the core, nor here)."""

from __future__ import annotations

import numpy as np


class FakeTensor:
    """Quacks like a torch tensor on a GPU with grad: detach() -> cpu() -> numpy(); ``calls``
    records the first two."""

    def __init__(self, a: np.ndarray):
        self.a = a
        self.calls: list[str] = []

    def detach(self) -> "FakeTensor":
        self.calls.append("detach")
        return self

    def cpu(self) -> "FakeTensor":
        self.calls.append("cpu")
        return self

    def numpy(self) -> np.ndarray:
        return self.a

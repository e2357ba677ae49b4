"""The anchor push of overlapping feet: the shortest grid move that clears the other foot, the C
kernel giving the numpy search's moves bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.retarget import anchor_gap, native
from motion2robot.retarget.anchor_gap import STEPS, _push, segment_distance


def _cases(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        seg = rng.normal(size=(2, 2)) * 0.05
        yield seg, seg + rng.normal(size=(2, 2)) * 0.02, abs(rng.normal()) * 0.04


def test_the_push_is_the_shortest_grid_move_that_clears():
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(native, "library", lambda: None)  # the numpy search
        for seg, other, need in _cases(200, seed=1):
            move = _push(seg, other, need)
            length = np.linalg.norm(move)
            if segment_distance(seg[0], seg[1], other[0], other[1]) >= need:
                assert length == 0.0
                continue
            assert segment_distance(seg[0] + move, seg[1] + move, other[0], other[1]) >= need or length == STEPS[-1]
            shorter = anchor_gap._MOVES[STEPS < length - 1e-12]                      # (s, D, 2)
            gaps = segment_distance(seg[0] + shorter, seg[1] + shorter, other[0], other[1])
            assert not (gaps >= need).any()


def test_the_compiled_push_gives_the_numpy_moves():
    if native.library() is None:
        pytest.skip("no C compiler: the numpy search runs")
    compiled = [_push(*case) for case in _cases(2000)]
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(native, "library", lambda: None)
        python = [_push(*case) for case in _cases(2000)]
    assert all(np.array_equal(a, b) for a, b in zip(compiled, python))
    assert sum(bool(np.any(m)) for m in python) > 1000  # most cases needed a push

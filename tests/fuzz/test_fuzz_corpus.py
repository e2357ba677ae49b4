"""A fast sample of the malformed-input corpus (tests/fuzz/corpus.py): each case must be one
``motion2robot: error: ...`` line and exit code 2. ``python scripts/fuzz_user_errors.py`` runs
every case."""

from __future__ import annotations

import pytest

from tests.fuzz.corpus import CASES
from tests.fuzz.runner import run_case

SAMPLE = CASES[::6]  # spread over every group of the corpus, a few seconds in all


def test_the_corpus_is_big_and_its_names_are_unique():
    assert len(CASES) >= 150
    assert len({c.name for c in CASES}) == len(CASES)


@pytest.mark.parametrize("case", SAMPLE, ids=[c.name for c in SAMPLE])
def test_user_error_is_one_line_and_exit_2(case, tmp_path):
    out = run_case(case, tmp_path)
    assert out.handled, out.describe()

"""Signed distance to the convex hull of the support points."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.validate.polygon import signed_distance

SQUARE = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5], [5, 5], [0, 0], [0, 0]], float)
QUERIES = np.array([[0.5, 0.5], [0.1, 0.5], [2, 0.5], [2, 2], [-1, 0.5]])


def run(active):
    T = len(QUERIES)
    return signed_distance(np.tile(SQUARE, (T, 1, 1)), np.tile(np.asarray(active, bool), (T, 1)), QUERIES)


def test_inside_positive_outside_negative():
    d = run([1, 1, 1, 1, 1, 0, 0, 0])
    np.testing.assert_allclose(d, [0.5, 0.1, -1.0, -np.sqrt(2), -1.0])


def test_duplicates_and_extra_points_make_the_right_hull():
    # hull (0,0) (1,0) (5,5) (0,1): (2, 0.5) is outside the edge (1,0)-(5,5), (2,2) inside
    d = run([1] * 8)
    assert d[2] == pytest.approx(-3 / np.sqrt(41))
    assert d[3] == pytest.approx(3 / np.sqrt(41))


def test_segment_and_point_hulls_have_everything_outside():
    seg = run([1, 1, 0, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(seg[:2], [-0.5, -0.5])
    pt = run([0, 0, 1, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(pt, -np.linalg.norm(QUERIES - [1, 1], axis=1))


def test_no_support_and_nan_queries_give_nan():
    assert np.isnan(run([0] * 8)).all()
    pts = np.tile(SQUARE, (1, 1, 1))
    assert np.isnan(signed_distance(pts, np.ones((1, 8), bool), np.array([[np.nan, 0.0]])))[0]


def test_several_queries_at_once():
    T = len(QUERIES)
    q = np.stack([QUERIES, QUERIES[::-1]], axis=1)
    both = signed_distance(np.tile(SQUARE, (T, 1, 1)), np.tile(np.array([1, 1, 1, 1, 0, 0, 0, 0], bool), (T, 1)), q)
    assert both.shape == (T, 2)
    np.testing.assert_allclose(both[:, 0], run([1, 1, 1, 1, 0, 0, 0, 0]))

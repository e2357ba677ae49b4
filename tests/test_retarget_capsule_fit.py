"""The capsule fitted to a point cloud holds every point and is as thin as the cloud allows."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.retarget.anchor_gap import segment_distance
from motion2robot.retarget.capsule_fit import enclosing_circle, fit_capsule



def test_holds_every_point_of_a_rotated_cylinder_and_is_tight():
    rng = np.random.default_rng(0)
    k = 4000
    ang, z = rng.uniform(0, 2 * np.pi, k), rng.uniform(-0.15, 0.15, k)
    pts = np.column_stack([0.05 * np.cos(ang), 0.05 * np.sin(ang), z])     # shell r = 5 cm, 30 cm long
    rot = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    pts = pts @ rot.T + np.array([0.1, -0.2, 0.3])
    p0, p1, r = fit_capsule(pts)
    assert np.all(segment_distance(pts, pts, p0, p1) <= r + 1e-12)
    assert 0.049 < r < 0.052                                                # the shell's radius (+ centroid offset)
    axis = (p1 - p0) / np.linalg.norm(p1 - p0)
    assert abs(abs(axis @ rot[:, 2]) - 1) < 1e-3                           # along the cylinder
    # the bounding box's capsule (cross half-diagonal) would be ~41 % fatter
    assert r < 0.75 * np.sqrt(2) * 0.05


def test_a_ball_of_points_gives_a_sphere_like_capsule():
    rng = np.random.default_rng(1)
    v = rng.normal(size=(2000, 3))
    pts = 0.02 * v / np.linalg.norm(v, axis=1, keepdims=True)
    p0, p1, r = fit_capsule(pts)
    assert np.all(segment_distance(pts, pts, p0, p1) <= r + 1e-12)
    assert r <= 0.021 and np.linalg.norm(p1 - p0) < 0.01


def test_single_point():
    p0, p1, r = fit_capsule(np.array([[1.0, 2.0, 3.0]]))
    assert r == 0.0 and np.allclose(p0, [1, 2, 3]) and np.allclose(p1, [1, 2, 3])


def _brute_force_circle(pts):
    """Smallest circle through 2 or 3 of the points that holds all of them."""
    from itertools import combinations

    from motion2robot.retarget.capsule_fit import _circle_2, _circle_3

    best = np.inf
    cands = [_circle_2(tuple(a), tuple(b)) for a, b in combinations(pts, 2)]
    cands += [_circle_3(tuple(a), tuple(b), tuple(c)) for a, b, c in combinations(pts, 3)]
    for cx, cy, r in cands:
        if np.all(np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) <= r + 1e-9):
            best = min(best, r)
    return best


def test_enclosing_circle_is_the_smallest():
    rng = np.random.default_rng(2)
    for n in (2, 3, 5, 9, 14):
        pts = rng.normal(size=(n, 2)) * [1.0, 0.3]
        c, r = enclosing_circle(pts)
        assert np.all(np.linalg.norm(pts - c, axis=1) <= r + 1e-9)
        assert r == pytest.approx(_brute_force_circle(pts), abs=1e-9)


def test_thinner_than_the_principal_axis_capsule_on_an_l_shape_and_holds_it():
    """An L-shaped cloud (a 10 cm bar with a spur at one end, rotated): the capsule about the
    principal axis through the centroid is off-centre; the searched axis through the enclosing
    circle's centre is more than 15 % thinner."""
    rng = np.random.default_rng(3)
    rot = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    arm = np.column_stack([rng.uniform(0, 0.10, 500), rng.uniform(-0.01, 0.01, 500), rng.uniform(-0.01, 0.01, 500)])
    foot = np.column_stack([rng.uniform(0.08, 0.10, 200), rng.uniform(-0.01, 0.01, 200), rng.uniform(-0.04, 0.01, 200)])
    pts = np.concatenate([arm, foot]) @ rot.T
    p0, p1, r = fit_capsule(pts)
    assert np.all(segment_distance(pts, pts, p0, p1) <= r + 1e-9)
    # the principal axis through the centroid (the previous fit): radius = farthest point from that line
    centre = pts.mean(axis=0)
    axis = np.linalg.svd(pts - centre)[2][0]
    rel = pts - centre
    r_pca = np.linalg.norm(rel - np.outer(rel @ axis, axis), axis=1).max()
    assert r < 0.85 * r_pca

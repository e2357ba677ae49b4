"""The capsule fitted to a point cloud holds every point and is as thin as the cloud allows."""

from __future__ import annotations

import numpy as np

from motion2robot.retarget.anchor_gap import segment_distance
from motion2robot.retarget.capsule_fit import fit_capsule



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

"""The polytope (26-DOP) of a body holds its geoms, and its capsule clearance never overstates
the true distance; the symbolic clearance equals the numeric one."""

from __future__ import annotations

import casadi as ca
import mujoco
import numpy as np
import pytest

from motion2robot.retarget.polytope import (
    DIRECTIONS,
    BodyPolytope,
    body_polytope,
    clearance_np,
    clearance_sx,
    geom_support,
    sphere_cover,
)

XML = """
<mujoco>
  <worldbody>
    <body name="b">
      <geom name="box" type="box" size="0.05 0.03 0.02" pos="0.01 0 0" euler="10 20 30"/>
      <geom name="sphere" type="sphere" size="0.02" pos="0 0.1 0"/>
      <geom name="capsule" type="capsule" size="0.015 0.04" pos="0 -0.1 0" euler="0 45 0"/>
      <geom name="cylinder" type="cylinder" size="0.02 0.03" pos="0.1 0.05 0" euler="30 0 60"/>
      <geom name="ellipsoid" type="ellipsoid" size="0.03 0.02 0.01" pos="-0.1 0 0.05" euler="0 30 0"/>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.fixture(scope="module")
def model():
    return mujoco.MjModel.from_xml_string(XML)


def _surface_samples(m, g, n=4000, seed=0):
    """Points on geom g's surface (body frame) via MuJoCo's own ray casts from its centre."""
    rng = np.random.default_rng(seed)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    centre = d.geom_xpos[g]
    dirs = rng.normal(size=(n, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    pts = []
    geomid = np.zeros(1, dtype=np.int32)
    for v in dirs:  # cast inwards from outside: the first hit is on the surface
        start = centre + 0.5 * v
        dist = mujoco.mj_ray(m, d, start, -v, None, 1, -1, geomid)
        if dist >= 0 and geomid[0] == g:
            pts.append(start - dist * v)
    return np.array(pts)  # body b is at the origin, unrotated: world = body frame


@pytest.mark.parametrize("name", ["box", "sphere", "capsule", "cylinder", "ellipsoid"])
def test_support_is_exact_per_geom_type(model, name):
    # the geom alone in a model of its own (no other geom shadows its rays)
    line = next(x for x in XML.splitlines() if f'name="{name}"' in x)
    alone = mujoco.MjModel.from_xml_string(f"<mujoco><worldbody><body name='b'>{line}</body></worldbody></mujoco>")
    pts = _surface_samples(alone, 0, n=40000)
    assert len(pts) > 30000
    h = geom_support(alone, 0, DIRECTIONS, None)
    reach = (pts @ DIRECTIONS.T).max(axis=0)
    assert np.all(reach <= h + 1e-9)          # holds the geom
    assert np.all(h - reach < 1.5e-3)          # and touches it (up to the sampling)


def test_clearance_never_overstates_the_distance_to_a_box(model):
    body = model.body("b").id
    poly = body_polytope(model, body, [(model.geom("box").id, None)])
    rng = np.random.default_rng(4)
    d = mujoco.MjData(model)
    mujoco.mj_kinematics(model, d)
    pose = (np.zeros(3), np.eye(3))
    box = model.geom("box").id
    checked = 0
    for _ in range(300):
        a = rng.uniform(-0.15, 0.15, 3)
        b = a + rng.normal(size=3) * 0.05
        r = 0.01
        clr = clearance_np(poly, pose, a, b, r)
        # the true distance from the box: sample the capsule's surface densely
        ts = np.linspace(0, 1, 60)
        seg = a + ts[:, None] * (b - a)
        rot = d.geom_xmat[box].reshape(3, 3)
        local = (seg - d.geom_xpos[box]) @ rot                   # segment points in the box frame
        outside = np.maximum(np.abs(local) - model.geom_size[box], 0.0)
        true_gap = np.linalg.norm(outside, axis=1).min() - r      # point-box distance (0 inside)
        if true_gap > 0:
            assert clr <= true_gap + 1e-9
            checked += 1
    assert checked > 100


def test_symbolic_clearance_matches_numeric(model):
    poly = BodyPolytope(0, DIRECTIONS.copy(), np.full(len(DIRECTIONS), 0.05))
    rng = np.random.default_rng(5)
    a, b = rng.uniform(-0.2, 0.2, 3), rng.uniform(-0.2, 0.2, 3)
    rot = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    pos = rng.normal(size=3) * 0.05
    r = 0.02
    A, B, O = ca.SX.sym("a", 3), ca.SX.sym("b", 3), ca.SX.sym("o", 3)
    axes = [ca.SX.sym(f"e{i}", 3) for i in range(3)]
    rows = clearance_sx(poly, O, axes, A, B, float(np.linalg.norm(b - a)), r)
    f = ca.Function("f", [A, B, O, *axes], [rows])
    sym = np.array(f(a, b, pos, *rot.T)).ravel()
    assert len(sym) == len(sphere_cover(a, b, r)[0])
    assert sym.min() == pytest.approx(clearance_np(poly, (pos, rot), a, b, r), abs=1e-12)


def test_sphere_cover_holds_the_capsule():
    a, b, r = np.zeros(3), np.array([0.1, 0.0, 0.0]), 0.03
    ts, rs = sphere_cover(a, b, r)
    centres = a + ts[:, None] * (b - a)
    rng = np.random.default_rng(6)
    s = rng.uniform(0, 1, 2000)
    v = rng.normal(size=(2000, 3))
    v[:, 0] = 0
    v = r * v / np.linalg.norm(v, axis=1)[:, None]
    surface = a + s[:, None] * (b - a) + v                       # the cylinder part's surface
    assert np.all(np.linalg.norm(surface[:, None] - centres[None], axis=2).min(axis=1) <= rs + 1e-12)


@pytest.mark.parametrize("name", ["box", "sphere", "capsule", "cylinder", "ellipsoid"])
def test_containing_capsule_holds_each_primitive(name):
    """The capsule fitted to a primitive's hull points (collision._geom_points) holds the whole
    geom: a flat cylinder's bounding-box capsule, a sphere, cut its rim (Unitree H1 hip yaw)."""
    from motion2robot.retarget.anchor_gap import segment_distance
    from motion2robot.retarget.capsule_fit import fit_capsule
    from motion2robot.retarget.collision import _geom_points

    line = next(x for x in XML.splitlines() if f'name="{name}"' in x)
    alone = mujoco.MjModel.from_xml_string(f"<mujoco><worldbody><body name='b'>{line}</body></worldbody></mujoco>")
    p0, p1, r = fit_capsule(_geom_points(alone, 0))
    pts = _surface_samples(alone, 0, n=20000)
    assert np.all(segment_distance(pts, pts, p0, p1) <= r + 1e-9)

"""Self-collision model on a mesh robot (Unitree G1): capsules fitted to the meshes hold every
vertex and are thinner than the bounding-box ones, and the hands are kept off each other and off the
pelvis."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.retarget.anchor_gap import segment_distance
from motion2robot.retarget.collision import _mesh_vertices, body_capsules, collision_pairs
from motion2robot.robot import load_robot
from tests._shared import MENAGERIE, requires_menagerie

pytestmark = requires_menagerie


@pytest.fixture(scope="module")
def g1():
    import os

    old = os.environ.get("MENAGERIE_ROOT")
    os.environ["MENAGERIE_ROOT"] = str(MENAGERIE)
    try:
        yield load_robot("menagerie:unitree_g1")
    finally:
        if old is None:
            os.environ.pop("MENAGERIE_ROOT")
        else:
            os.environ["MENAGERIE_ROOT"] = old



def test_mesh_capsules_hold_their_vertices_and_are_thinner_than_boxes(g1):
    m = g1.model
    fitted = body_capsules(m, contain=True)
    boxes = body_capsules(m)
    checked = 0
    for b, cap in fitted.items():
        verts = [_mesh_vertices(m, g) for g in range(m.ngeom) if m.geom_bodyid[g] == b
                 and (m.geom_contype[g] or m.geom_conaffinity[g])]
        if not verts or any(v is None for v in verts):
            continue
        pts = np.concatenate(verts)
        assert segment_distance(pts, pts, cap.p0, cap.p1).max() <= cap.radius + 1e-9
        checked += 1
    assert checked >= 15
    hip_yaw = m.body("left_hip_yaw_link").id
    assert fitted[hip_yaw].radius < 0.7 * boxes[hip_yaw].radius


def test_pairs_keep_hands_apart_and_off_the_pelvis(g1):
    names = {p.name for p in collision_pairs(g1)}
    assert any("left_wrist" in n and "right_wrist" in n for n in names)
    assert any("pelvis" in n and "wrist" in n for n in names)
    assert len(names) == len(collision_pairs(g1))                          # no pair twice

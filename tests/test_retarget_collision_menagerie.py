"""Self-collision model on a mesh robot (Unitree G1): capsules fitted to the meshes hold every
vertex and are thinner than the bounding-box ones, and the hands are kept off each other and off the
pelvis."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.retarget.anchor_gap import segment_distance
from motion2robot.retarget.collision import _mesh_vertices, body_capsules, collision_pairs
from tests._shared import MOTIONS, load_menagerie, requires_menagerie, requires_shared

pytestmark = requires_menagerie


@pytest.fixture(scope="module")
def g1():
    return load_menagerie("menagerie:unitree_g1")



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


def test_upper_arms_are_kept_off_the_torso_by_its_polytope(g1):
    """G1's torso is modelled by its polytope against the arms: no capsule fits it without
    swallowing the upper arm at the nominal posture (the pair was dropped before)."""
    from motion2robot.retarget.polytope import BodyPolytope

    pairs = {p.name: p for p in collision_pairs(g1)}
    for side in ("left", "right"):
        pair = pairs[f"{side}_shoulder_yaw_link-torso_link"]
        assert isinstance(pair.b, BodyPolytope) and pair.allowance == 0.0
        assert f"{side}_shoulder_roll_link-torso_link" in pairs


@requires_shared
def test_g1_kick_keeps_the_arms_out_of_the_torso(g1):
    """A boxer's guard (bandai kick, frames 0-80) put G1's upper arms 20-48 mm into its torso;
    the polytope pairs and the damped extra projection steps keep them out (MuJoCo's geoms)."""
    from motion2robot.motion import read_motion
    from motion2robot.motion.ops import trim
    from motion2robot.retarget import RetargetOptions, whole_body as retarget
    from motion2robot.retarget.metrics import acceptance

    human = trim(read_motion(MOTIONS / "bvh" / "bandai_kick_normal_001.bvh")[0], 0, 80)
    motion = retarget(human, g1, RetargetOptions(balance=False))
    assert motion.meta["solver"]["max_constraint_residuals"]["self_collision"] < 0.002
    assert acceptance(motion, g1)["self_collision_mm"] < 2.0

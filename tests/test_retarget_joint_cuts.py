"""Joint-space self-collision cuts (pairs one or two hinges apart): the cut-finding on synthetic
maps, the real maps of the OP3 and the G1 (MuJoCo's distance on random postures the cuts keep),
the disk cache, and the G1 dance whose hip-roll link went 15 mm into the pelvis."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from motion2robot.retarget import joint_cuts as jc
from motion2robot.retarget.collision import collision_pairs
from motion2robot.robot import load_robot
from motion2robot.validate.models import check_model
from tests._shared import MOTIONS, load_menagerie, requires_menagerie, requires_shared


def _grid(n: int) -> np.ndarray:
    return jc._grid(2, n)


def test_cuts_leave_out_a_frame_of_colliding_postures_and_keep_the_inside():
    """Limits that collide (the G1's wrist links meet at the ends of their ranges): four cuts
    parallel to the box's sides, nothing of the inside lost."""
    u = _grid(41)
    bad = (u < 0.06).any(axis=1) | (u > 0.94).any(axis=1)
    cuts = jc.greedy_cuts(u, bad, np.array([0.5, 0.5]), 0.5 / 40)
    assert cuts is not None and len(cuts) == 4
    kept = np.all([u @ n <= c for n, c in cuts], axis=0)
    assert not (kept & bad).any()
    assert np.count_nonzero(kept) == np.count_nonzero(~bad)


def test_a_corner_is_cut_by_one_slanted_half_plane():
    u = _grid(41)
    bad = u.sum(axis=1) > 1.6
    (n, c), = jc.greedy_cuts(u, bad, np.array([0.3, 0.3]), 0.5 / 40)
    assert np.allclose(n, [2 ** -0.5, 2 ** -0.5], atol=0.02)
    kept = u @ n <= c
    assert not (kept & bad).any() and np.count_nonzero(kept) >= 0.95 * np.count_nonzero(~bad)


def test_no_cut_can_keep_a_colliding_nominal_posture():
    u = _grid(11)
    bad = np.linalg.norm(u - 0.5, axis=1) < 0.2
    assert jc.greedy_cuts(u, bad, np.array([0.5, 0.5]), 0.05) is None


def test_op3_needs_no_cuts():
    """Its closest pair within two hinges (knee and ankle-roll links) never meets in the ranges."""
    op3 = load_robot("op3")
    pairs = jc.candidate_pairs(op3, {tuple(sorted((p.a.body, p.b.body))) for p in collision_pairs(op3)})
    assert any("knee" in jc.body_name(op3.model, a) and "ank_roll" in jc.body_name(op3.model, b) for a, b, _ in pairs)
    assert jc.joint_cuts(op3, {tuple(sorted((p.a.body, p.b.body))) for p in collision_pairs(op3)}) == ()


@pytest.fixture(scope="module")
def g1():
    return load_menagerie("menagerie:unitree_g1")


def _modelled(robot) -> set[tuple[int, int]]:
    return {tuple(sorted((p.a.body, p.b.body))) for p in collision_pairs(robot)}


@requires_menagerie
def test_g1_cuts_keep_pelvis_and_hip_roll_links_apart_on_random_postures(g1):
    """Postures the cuts keep never put the geoms into each other (MuJoCo's distance), and the
    cuts keep most of the ranges."""
    cuts = jc.joint_cuts(g1, _modelled(g1))
    names = {c.name for c in cuts}
    assert {"pelvis-left_hip_roll_link", "pelvis-right_hip_roll_link"} <= names
    m = check_model(g1)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(1)
    hinge = {int(j): i for i, j in enumerate(g1.joint_ids)}
    for side in ("left", "right"):
        mine = [c for c in cuts if c.name == f"pelvis-{side}_hip_roll_link"]
        joints = [m.joint(f"{side}_hip_pitch_joint").id, m.joint(f"{side}_hip_roll_joint").id]
        lo = np.array([g1.lower[hinge[j]] for j in joints])
        hi = np.array([g1.upper[hinge[j]] for j in joints])
        q = np.tile(g1.nominal_qpos, (1500, 1))
        q[:, mine[0].qpos_index] = lo + rng.random((1500, 2)) * (hi - lo)
        kept = np.all([c.gap_np(q) >= 0 for c in mine], axis=0)
        assert kept.mean() > 0.85
        geoms = [[g for g in range(m.ngeom) if m.geom_bodyid[g] == m.body(b).id and m.geom_contype[g]]
                 for b in ("pelvis", f"{side}_hip_roll_link")]
        ft = np.zeros(6)
        dist = []
        for x in q:
            d.qpos[:] = x
            mujoco.mj_kinematics(m, d)
            dist.append(min(mujoco.mj_geomDistance(m, d, a, b, 0.05, ft) for a in geoms[0] for b in geoms[1]))
        dist = np.array(dist)
        assert dist[kept].min() > 0.0          # kept postures: apart
        assert dist[~kept].min() < -0.005      # and the cuts leave out postures that really collide


@requires_menagerie
def test_g1_cuts_come_from_the_disk_cache_the_second_time(g1, tmp_path, monkeypatch):
    monkeypatch.setenv("MOTION2ROBOT_CACHE", str(tmp_path))
    first = jc.joint_cuts(g1, _modelled(g1))
    assert len(list((tmp_path / "cuts").glob("*.json"))) == 1

    def no_mapping(*_a, **_k):
        raise AssertionError("mapped again")

    monkeypatch.setattr(jc, "_map_pairs", no_mapping)
    again = jc.joint_cuts(g1, _modelled(g1))
    assert [(c.name, c.offset) for c in again] == [(c.name, c.offset) for c in first]
    assert all(np.array_equal(a.normal, b.normal) and np.array_equal(a.qpos_index, b.qpos_index)
               for a, b in zip(first, again))
    next((tmp_path / "cuts").glob("*.json")).write_text("{not json")
    monkeypatch.undo()
    monkeypatch.setenv("MOTION2ROBOT_CACHE", str(tmp_path))
    assert [c.name for c in jc.joint_cuts(g1, _modelled(g1))] == [c.name for c in first]  # a broken file: mapped again


@requires_menagerie
@requires_shared
def test_g1_dance_keeps_the_hip_roll_links_out_of_the_pelvis(g1):
    """bandai dance-short, frames 280-360: the hip-roll links went 12-15 mm into the pelvis (a pair
    no capsule models); the joint-space cuts keep them out (MuJoCo's geoms)."""
    from motion2robot.motion import read_motion
    from motion2robot.motion.ops import trim
    from motion2robot.retarget import RetargetOptions, whole_body as retarget
    from motion2robot.retarget.metrics import acceptance

    human = trim(read_motion(MOTIONS / "bvh" / "bandai_dance-short_normal_001.bvh")[0], 280, 360)
    motion = retarget(human, g1, RetargetOptions(balance=False))
    assert motion.meta["solver"]["max_constraint_residuals"]["self_collision"] < 0.002
    assert acceptance(motion, g1)["self_collision_mm"] < 2.0

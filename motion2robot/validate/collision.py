"""Self-collision: robot-robot contacts deeper than ``collision_depth``, judged as MuJoCo sees the model.

Pairs judged: exactly the geom pairs MuJoCo's collision detection tests in the robot's own model
(:func:`~motion2robot.robot.collision_filter.tested_geom_pairs`: weld bodies, parent-child per
``filterparent``, ``<exclude>``, contype/conaffinity, ``<pair>``). A geom pair that already
overlaps at the robot's nominal posture (``nominal_overlaps``: the model itself overlaps there) is
judged only by how much the motion deepens it; every other pair by its whole depth.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import mujoco
import numpy as np

from motion2robot.robot.collision_filter import tested_geom_pairs
from motion2robot.robot.robot import Robot
from motion2robot.validate.context import Context
from motion2robot.validate.frames import frame_list
from motion2robot.validate.models import body_name, check_model, floor_geom, mujoco_world_model


@dataclass(frozen=True, eq=False)
class PairTable:
    """On :func:`~motion2robot.validate.models.check_model`'s geom ids: ``judged`` (ngeom, ngeom)
    robot-robot geom pairs MuJoCo tests in the robot's own model; ``nominal`` (ngeom, ngeom) their
    penetration depth (m, >= 0) at the nominal posture."""

    judged: np.ndarray
    nominal: np.ndarray

    def excess(self, geom1: np.ndarray, geom2: np.ndarray, dist: np.ndarray) -> np.ndarray:
        """Depth (m) of contacts beyond the pair's nominal overlap; -inf for pairs not judged."""
        depth = -np.asarray(dist, float) - self.nominal[geom1, geom2]
        return np.where(self.judged[geom1, geom2], depth, -np.inf)


@functools.lru_cache(maxsize=8)
def pair_table(robot: Robot) -> PairTable:
    """The robot's :class:`PairTable` (cached per robot)."""
    m = check_model(robot)
    judged = tested_geom_pairs(mujoco_world_model(robot))
    floor = floor_geom(m)
    world = m.geom_bodyid == 0
    judged[world, :] = judged[:, world] = False
    judged[floor, :] = judged[:, floor] = False
    nominal = np.zeros(judged.shape)
    d = mujoco.MjData(m)
    d.qpos[:] = robot.nominal_qpos
    mujoco.mj_kinematics(m, d)
    mujoco.mj_collision(m, d)
    for c in d.contact[: d.ncon]:
        g1, g2 = int(c.geom[0]), int(c.geom[1])
        if judged[g1, g2] and c.dist < 0:
            nominal[g1, g2] = nominal[g2, g1] = max(nominal[g1, g2], -float(c.dist))
    return PairTable(judged, nominal)


@functools.lru_cache(maxsize=8)
def ignored_body_pairs(robot: Robot) -> frozenset[tuple[int, int]]:
    """Collidable body pairs (a < b) whose contacts do not count as they are: MuJoCo does not test
    them, or they overlap at the nominal posture (judged by the deepening only)."""
    m = check_model(robot)
    t = pair_table(robot)
    coll = np.unique(m.geom_bodyid[(m.geom_contype != 0) | (m.geom_conaffinity != 0)])
    coll = coll[coll != 0]
    tested = np.zeros((m.nbody, m.nbody), dtype=bool)
    g1, g2 = np.nonzero(t.judged & (t.nominal == 0))
    tested[m.geom_bodyid[g1], m.geom_bodyid[g2]] = True
    overlap = np.zeros_like(tested)
    g1, g2 = np.nonzero(t.nominal > 0)
    overlap[m.geom_bodyid[g1], m.geom_bodyid[g2]] = True
    return frozenset((int(a), int(b)) for i, a in enumerate(coll) for b in coll[i + 1:]
                     if not tested[a, b] or overlap[a, b])


def nominal_overlaps(robot: Robot) -> list[dict]:
    """Body pairs whose geoms MuJoCo tests and which overlap at the nominal posture, deepest first:
    ``{"body1", "body2", "nominal_depth_m"}``."""
    m = check_model(robot)
    t = pair_table(robot)
    best: dict[tuple[int, int], float] = {}
    for g1, g2 in zip(*np.nonzero(np.triu(t.nominal > 0))):
        key = tuple(sorted((int(m.geom_bodyid[g1]), int(m.geom_bodyid[g2]))))
        best[key] = max(best.get(key, 0.0), float(t.nominal[g1, g2]))
    return [{"body1": body_name(m, a), "body2": body_name(m, b), "nominal_depth_m": round(v, 4)}
            for (a, b), v in sorted(best.items(), key=lambda kv: -kv[1])]


def self_collision(ctx: Context) -> dict:
    """Robot-robot contacts deeper than ``collision_depth`` (m) beyond the model's own nominal
    overlap, grouped by body pair; ``nominal_overlaps`` lists where the model itself overlaps."""
    m, c = ctx.kin.model, ctx.kin.contacts
    t = pair_table(ctx.robot)
    excess = t.excess(c.geom1, c.geom2, c.dist)
    keep = np.isfinite(excess)
    deep = keep & (excess > ctx.options.collision_depth)
    b1, b2 = m.geom_bodyid[c.geom1], m.geom_bodyid[c.geom2]
    lo, hi = np.minimum(b1, b2), np.maximum(b1, b2)
    bad = np.zeros(ctx.kin.num_frames, dtype=bool)
    bad[c.frame[deep]] = True
    overlaps = {(o["body1"], o["body2"]): o["nominal_depth_m"] for o in nominal_overlaps(ctx.robot)}
    viol = []
    if deep.any():
        keys = np.stack([lo[deep], hi[deep]], axis=1)
        for a, b in np.unique(keys, axis=0):
            sel = deep & (lo == a) & (hi == b)
            k = np.argmax(excess[sel])
            v = {"body1": body_name(m, a), "body2": body_name(m, b),
                 "depth_m": round(float(excess[sel][k]), 4),
                 "worst_frame": int(c.frame[sel][k]),
                 "frames": sorted({int(f) for f in c.frame[sel]})}
            nominal = overlaps.get((v["body1"], v["body2"]))
            if nominal is not None:
                v["nominal_depth_m"] = nominal
            viol.append(v)
        viol.sort(key=lambda v: -v["depth_m"])
    max_depth = float(excess[keep].max()) if keep.any() else 0.0
    return {"ok": not bad.any(), "frames": frame_list(bad), "max_depth_m": round(max(max_depth, 0.0), 4),
            "violations": viol, "nominal_overlaps": [{"body1": a, "body2": b, "nominal_depth_m": v}
                                                     for (a, b), v in overlaps.items()]}

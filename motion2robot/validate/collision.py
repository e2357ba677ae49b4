"""Self-collision: robot-robot contacts deeper than ``collision_depth``.

Pairs that never count: kinematic neighbours (a body and its nearest collidable ancestor, see
:func:`~motion2robot.validate.models.adjacent_body_pairs`), the MJCF's own ``<exclude>`` pairs
(MuJoCo drops them), and pairs already interpenetrating at the robot's nominal posture (overlaps
of the model's collision hulls by design, not caused by the motion).
"""

from __future__ import annotations

import functools

import mujoco
import numpy as np

from motion2robot.robot.robot import Robot
from motion2robot.validate.context import Context
from motion2robot.validate.frames import frame_list
from motion2robot.validate.models import (
    adjacent_body_pairs,
    body_name,
    check_model,
    floor_geom,
)


@functools.lru_cache(maxsize=8)
def ignored_body_pairs(robot: Robot) -> frozenset[tuple[int, int]]:
    """Body pairs (a < b) whose contacts are not self-collisions (neighbours, overlapping at nominal)."""
    m = check_model(robot)
    pairs = set(adjacent_body_pairs(m))
    d = mujoco.MjData(m)
    d.qpos[:] = robot.nominal_qpos
    mujoco.mj_kinematics(m, d)
    mujoco.mj_collision(m, d)
    floor = floor_geom(m)
    for c in d.contact[: d.ncon] if d.ncon else []:
        g1, g2 = int(c.geom[0]), int(c.geom[1])
        if floor in (g1, g2):
            continue
        a, b = sorted((int(m.geom_bodyid[g1]), int(m.geom_bodyid[g2])))
        pairs.add((a, b))
    return frozenset(pairs)


def self_collision(ctx: Context) -> dict:
    """Robot-robot contacts deeper than ``collision_depth`` (m), grouped by body pair."""
    m, c = ctx.kin.model, ctx.kin.contacts
    floor = floor_geom(m)
    b1, b2 = m.geom_bodyid[c.geom1], m.geom_bodyid[c.geom2]
    lo, hi = np.minimum(b1, b2), np.maximum(b1, b2)
    ignored = ignored_body_pairs(ctx.robot)
    robot_pair = (c.geom1 != floor) & (c.geom2 != floor) & (lo != 0)
    skip = np.zeros((m.nbody, m.nbody), dtype=bool)
    for a, b in ignored:
        skip[a, b] = True
    keep = robot_pair & ~skip[lo, hi]
    deep = keep & (c.dist < -ctx.options.collision_depth)
    bad = np.zeros(ctx.kin.num_frames, dtype=bool)
    bad[c.frame[deep]] = True
    viol = []
    if deep.any():
        keys = np.stack([lo[deep], hi[deep]], axis=1)
        for a, b in np.unique(keys, axis=0):
            sel = deep & (lo == a) & (hi == b)
            k = np.argmin(c.dist[sel])
            viol.append({"body1": body_name(m, a), "body2": body_name(m, b),
                         "depth_m": round(float(-c.dist[sel][k]), 4),
                         "worst_frame": int(c.frame[sel][k]),
                         "frames": sorted({int(f) for f in c.frame[sel]})})
        viol.sort(key=lambda v: -v["depth_m"])
    max_depth = float(-c.dist[keep].min()) if keep.any() else 0.0
    return {"ok": not bad.any(), "frames": frame_list(bad), "max_depth_m": round(max(max_depth, 0.0), 4),
            "violations": viol}

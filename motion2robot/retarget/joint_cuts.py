"""Self-collision of bodies one or two hinges apart, kept in joint space (exactly as judged).

When at most two hinges lie on the kinematic path between two bodies, the bodies' relative pose,
and so the distance between their collision geoms, is a function of those angles alone. Such a
pair is mapped directly: MuJoCo's own distance (``mj_geomDistance`` on the collision geoms of the
validator's model, :func:`~motion2robot.validate.models.check_model`) on a grid over the joints'
ranges. If the geoms meet somewhere in the ranges, the postures closer than
:data:`CUT_CLEARANCE` are cut off the range box by half-planes ``normal . q <= offset`` (unit
normal, angles in rad) that keep the nominal posture (:func:`greedy_cuts`). The retargeter keeps
``gap = lever * (offset - normal . q) >= 0`` (m: the joint-space distance to the cut, rad, times
the bodies' reach from the joints, m) as one more self-collision row, linear in the angles.

This covers what capsules cannot: the G1's pelvis and hip-roll links are 26 mm apart at the
nominal posture but any capsules or polytopes containing them already touch there, so the capsule
model leaves the pair out (:func:`~motion2robot.retarget.collision.collision_pairs`), and a dance
put a hip-roll link 15 mm into the pelvis; its wrist links meet at the ends of their ranges.
Pairs considered: those the validator judges (the pairs MuJoCo tests,
:func:`~motion2robot.validate.collision.ignored_body_pairs` left out) that no capsule pair models. Pairs whose geoms never
meet within the ranges get no cut (the OP3 has none: its closest, knee and ankle-roll links, stay
1 mm apart at the corner of the ankle's ranges). The maps are cached on disk.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from motion2robot.robot.robot import Robot
from motion2robot.util.cache import cache_dir, write_atomic
from motion2robot.validate.collision import ignored_body_pairs, pair_table
from motion2robot.validate.models import body_name, check_model, collidable_bodies

#: Grid points per joint (two joints: GRID x GRID postures; one joint: GRID ** 2 / 16).
GRID = 61
#: Grid points per joint of the first, coarse look (see :func:`pair_cuts`).
COARSE = 9
#: Postures whose geoms are closer than this (m) count as colliding (for pairs that meet at all).
CUT_CLEARANCE = 0.002
#: Directions tried for a half-plane (evenly over the circle).
DIRECTIONS = 360
#: Distances beyond this (m) are not computed exactly (``mj_geomDistance``'s ``distmax``).
DISTMAX = 0.05


@dataclass(frozen=True, eq=False)
class JointCut:
    """Keep ``lever * (offset - normal . q[qpos_index]) >= 0``: ``qpos_index`` (k,) the hinges' qpos
    addresses (``dof_index`` their tangent-step addresses), ``normal`` (k,) a unit vector,
    ``offset`` (rad), ``lever`` (m)."""

    name: str
    qpos_index: np.ndarray
    dof_index: np.ndarray
    normal: np.ndarray
    offset: float
    lever: float

    def gap_np(self, qpos: np.ndarray) -> np.ndarray:
        """(T,) gaps (m; negative = on the colliding side) of (T, nq) qpos."""
        return self.lever * (self.offset - qpos[:, self.qpos_index] @ self.normal)


def _path_joints(m: mujoco.MjModel, a: int, b: int) -> list[int] | None:
    """The joints of the bodies on the tree path between ``a`` and ``b`` (below their common
    ancestor); None if one of them is not a hinge."""
    def up(x):
        out = []
        while x > 0:
            out.append(x)
            x = int(m.body_parentid[x])
        return out
    ua, ub = up(a), up(b)
    common = next((x for x in ua if x in ub), 0)
    bodies = [x for x in ua + ub if x not in up(common)]
    joints = [j for j in range(m.njnt) if int(m.jnt_bodyid[j]) in bodies]
    return joints if all(int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE) for j in joints) else None


def candidate_pairs(robot: Robot, modelled: set[tuple[int, int]]) -> list[tuple[int, int, list[int]]]:
    """(a, b, joints) for the body pairs (a < b) the validator judges, not in ``modelled``, with
    one or two hinges on the path between them."""
    m = check_model(robot)
    coll = np.flatnonzero(collidable_bodies(m))
    skip = set(ignored_body_pairs(robot)) | set(modelled)
    out = []
    for i, a in enumerate(coll):
        for b in coll[i + 1:]:
            a_, b_ = int(a), int(b)
            if a_ == 0 or (a_, b_) in skip:
                continue
            joints = _path_joints(m, a_, b_)
            if joints and len(joints) <= 2:
                out.append((a_, b_, joints))
    return out


def _distance_fn(robot: Robot, a: int, b: int, joints: list[int]):
    """(q (k,), distmax) -> the smallest distance (m, capped at distmax) between the two bodies' geoms."""
    m = check_model(robot)
    d = mujoco.MjData(m)
    judged = pair_table(robot).judged
    geoms = [[g for g in range(m.ngeom) if int(m.geom_bodyid[g]) == x and (m.geom_contype[g] or m.geom_conaffinity[g])]
             for x in (a, b)]
    pairs = [(x, y) for x in geoms[0] for y in geoms[1] if judged[x, y]]
    adr = [int(m.jnt_qposadr[j]) for j in joints]
    fromto = np.zeros(6)

    def dist(q: np.ndarray, distmax: float) -> float:
        d.qpos[:] = robot.nominal_qpos
        d.qpos[adr] = q
        mujoco.mj_kinematics(m, d)
        return min(mujoco.mj_geomDistance(m, d, x, y, distmax, fromto) for x, y in pairs)
    return dist


def _directions(k: int) -> np.ndarray:
    if k == 1:
        return np.array([[1.0], [-1.0]])
    ang = np.linspace(0, 2 * np.pi, DIRECTIONS, endpoint=False)
    return np.stack([np.cos(ang), np.sin(ang)], axis=1)


def greedy_cuts(u: np.ndarray, bad: np.ndarray, u_nom: np.ndarray, pad: float) -> list[tuple[np.ndarray, float]] | None:
    """Half-planes ``n . u <= c`` (grid coordinates ``u`` (P, k)) that together leave out every
    ``bad`` point by ``pad`` and keep ``u_nom``: the colliding point nearest the nominal posture
    not yet left out gets the half-plane through it (less ``pad``) that loses the fewest free
    points still kept (of those, the one leaving out the most colliding points), until none is
    left; then half-planes the others make redundant are dropped. None if a colliding point
    cannot be left out."""
    dirs = _directions(u.shape[1])
    proj = u @ dirs.T                        # (P, directions)
    nom = u_nom @ dirs.T
    kept = ~bad
    todo = np.flatnonzero(bad)
    todo = todo[np.argsort(np.linalg.norm(u[todo] - u_nom, axis=1))]
    out = []
    while todo.size:
        c = proj[todo[0]] - pad              # the half-plane through the nearest, per direction
        lost = np.count_nonzero(kept[:, None] & (proj > c), axis=0)
        gained = np.count_nonzero(proj[todo] > c, axis=0)
        score = np.where(nom < c, lost * (bad.size + 1) - gained, np.iinfo(np.int64).max)
        i = int(np.argmin(score))
        if nom[i] >= c[i]:
            return None
        out.append((dirs[i], float(c[i])))
        kept &= proj[:, i] <= c[i]
        todo = todo[proj[todo, i] <= c[i]]
    for cut in list(reversed(out)):          # the last ones were made for stragglers
        rest = [x for x in out if x is not cut]
        kept_by_rest = np.all([u @ n <= c for n, c in rest], axis=0) if rest else np.ones(len(u), dtype=bool)
        if not np.any(bad & kept_by_rest):
            out = rest
    return out


def _lever(m: mujoco.MjModel, d: mujoco.MjData, a: int, b: int, joints: list[int]) -> float:
    """The largest distance (m) from a path joint's anchor to the far side of either body's
    geoms at the nominal posture: how far an angle (rad) moves the bodies at most."""
    reach = 0.0
    for j in joints:
        for g in range(m.ngeom):
            if int(m.geom_bodyid[g]) in (a, b):
                reach = max(reach, float(np.linalg.norm(d.geom_xpos[g] - d.xanchor[j])) + float(m.geom_rbound[g]))
    return reach


def _grid(k: int, n_pts: int) -> np.ndarray:
    """(n_pts ** k, k) points of the unit box, row-major."""
    axes = [np.linspace(0.0, 1.0, n_pts)] * k
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, k)


def pair_cuts(robot: Robot, a: int, b: int, joints: list[int], lo: np.ndarray, hi: np.ndarray,
              lever: float) -> list[tuple[np.ndarray, float]]:
    """Half-planes ``normal . q <= offset`` (unit normal, rad) keeping bodies ``a`` and ``b`` apart
    over the box ``lo``..``hi`` (rad) of their path's ``joints``; [] if they never meet there.
    A coarse grid first: a pair farther apart than ``lever`` (m/rad) times half its cell
    everywhere on it cannot meet in between (most pairs: 81 postures instead of 3,721)."""
    k = len(joints)
    dist = _distance_fn(robot, a, b, joints)
    coarse = _grid(k, COARSE)
    if min(dist(lo + x * (hi - lo), 1.0) for x in coarse) > lever * float(np.sum(hi - lo)) / (2 * (COARSE - 1)):
        return []
    n_pts = GRID if k == 2 else GRID * GRID // 16
    u = _grid(k, n_pts)
    dd = np.array([dist(lo + x * (hi - lo), DISTMAX) for x in u])
    if dd.min() >= 0:
        return []  # the geoms never meet within the ranges (the OP3's knee and ankle: 1 mm at the corner)
    adr = [int(robot.model.jnt_qposadr[j]) for j in joints]
    u_nom = (robot.nominal_qpos[adr] - lo) / (hi - lo)
    out = []
    for n, c in greedy_cuts(u, dd < CUT_CLEARANCE, u_nom, 0.5 / (n_pts - 1)) or []:
        # back to angles: n . (q - lo) / (hi - lo) <= c, scaled so that the normal is a unit vector
        normal = n / (hi - lo)
        scale = float(np.linalg.norm(normal))
        out.append((normal / scale, (c + float(normal @ lo)) / scale))
    return out


#: MjModel arrays the cuts depend on (kinematics and collision geometry), for the cache key.
_MODEL_ARRAYS = ("body_parentid", "body_pos", "body_quat", "jnt_type", "jnt_bodyid", "jnt_qposadr", "jnt_dofadr",
                 "jnt_axis", "jnt_pos", "geom_type", "geom_size", "geom_pos", "geom_quat", "geom_bodyid",
                 "geom_dataid", "geom_contype", "geom_conaffinity", "geom_rbound", "mesh_vert", "mesh_vertadr",
                 "mesh_vertnum", "exclude_signature")


def joint_cuts(robot: Robot, modelled: set[tuple[int, int]]) -> tuple[JointCut, ...]:
    """The half-plane cuts of every candidate pair (module docstring), from the disk cache
    (:func:`~motion2robot.util.cache.cache_dir`, ``cuts/``) when this code has mapped this
    robot's geometry and ranges before (the G1's map takes ~1 s)."""
    pairs = candidate_pairs(robot, modelled)
    h = hashlib.sha256(Path(__file__).read_bytes())
    m = check_model(robot)
    for x in [mujoco.__version__, pairs] + [getattr(m, k) for k in _MODEL_ARRAYS] + \
            [robot.lower, robot.upper, np.asarray(robot.joint_ids), robot.nominal_qpos]:
        h.update(np.ascontiguousarray(x).tobytes() if isinstance(x, np.ndarray) else repr(x).encode())
    path = cache_dir() / "cuts" / f"{h.hexdigest()[:24]}.json"
    try:
        return tuple(JointCut(c["name"], np.array(c["qpos_index"]), np.array(c["dof_index"]), np.array(c["normal"]),
                              float(c["offset"]), float(c["lever"])) for c in json.loads(path.read_text()))
    except (OSError, ValueError, KeyError, TypeError):
        pass
    cuts = _map_pairs(robot, pairs)
    write_atomic(path, json.dumps([{"name": c.name, "qpos_index": c.qpos_index.tolist(), "dof_index": c.dof_index.tolist(),
                                    "normal": c.normal.tolist(), "offset": c.offset, "lever": c.lever} for c in cuts]))
    return cuts


def _map_pairs(robot: Robot, pairs: list[tuple[int, int, list[int]]]) -> tuple[JointCut, ...]:
    m = check_model(robot)
    d = mujoco.MjData(m)
    d.qpos[:] = robot.nominal_qpos
    mujoco.mj_kinematics(m, d)
    hinge_of = {int(j): i for i, j in enumerate(robot.joint_ids)}
    out = []
    for a, b, joints in pairs:
        if any(j not in hinge_of for j in joints):
            continue
        lo = np.array([robot.lower[hinge_of[j]] for j in joints])
        hi = np.array([robot.upper[hinge_of[j]] for j in joints])
        lever = _lever(m, d, a, b, joints)
        name = f"{body_name(m, a)}-{body_name(m, b)}"
        qadr = np.array([int(m.jnt_qposadr[j]) for j in joints])
        dadr = np.array([int(m.jnt_dofadr[j]) for j in joints])
        out += [JointCut(name, qadr, dadr, n, c, lever) for n, c in pair_cuts(robot, a, b, joints, lo, hi, lever)]
    return tuple(out)

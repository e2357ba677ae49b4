"""Self-collision model of the retargeter: one capsule per body, along the longest axis of the
bounding box (body frame) of the body's collision geoms, radius the larger cross half-extent
(for elongated boxes and meshes the segment spans the whole length so the corners stay inside),
for the largest bodies of each limb (:data:`LIMB_BODIES`), and the pairs that matter: left leg vs
right leg, the two arms and hands, every body of each arm (hand included) vs the torso, each hand (the wrist keypoint's body and below) vs every body
of its own leg and the largest of the other leg's. Torso bodies may be modelled by their polytope instead
(:mod:`~motion2robot.retarget.polytope`), whichever of the two containing models is tighter at the
nominal posture. Mesh bodies get capsules fitted to their vertices (:mod:`~motion2robot.retarget.capsule_fit`).

Boxes get a capsule containing them (over the whole length, radius the cross
half-diagonal) unless that capsule already touches the other one at the nominal posture, when the
inscribed capsule is used. Pairs MuJoCo does not test (:mod:`~motion2robot.robot.collision_filter`), and pairs already touching at the nominal posture, are left out
(overlaps of the model's hulls by design). Capsules may come closer than touching only by what
they provably overstate their geometry (:func:`overstatement`: the radius less the farthest hull
point's distance from the segment, the same in every direction), never more than
:data:`NOMINAL_CLEARANCE` below their clearance at the nominal posture. Capsules fitted to their
geometry overstate it by nothing in some direction, so they get no allowance: the overstatement a
pair shows at the nominal posture lies along the direction the nominal posture sets, and another
posture can bring the tight sides together (the drafted Talos' shin capsules, 14.5 mm wider than
the hulls along their nominal gap, let the shins 4.7 mm into each other under a 9.9 mm allowance).
Capsule distance = segment distance - radii (exact);
:data:`MARGIN` covers box corners outside their capsule. Pairs of bodies one or two hinges apart
that this model leaves out are kept apart in joint space (:mod:`~motion2robot.retarget.joint_cuts`).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import mujoco
import numpy as np

from motion2robot.retarget.capsule_fit import fit_capsule
from motion2robot.retarget.polytope import BodyPolytope, body_polytope, clearance_np, clearance_sx
from motion2robot.robot.collision_filter import tested_body_pairs
from motion2robot.robot.kinematics import quat_to_mat_np
from motion2robot.robot.robot import Robot

#: Capsules kept per limb: the largest bodies (legs: thigh, shin, foot, ankle and hip-roll links;
#: arms: upper arm, forearm; torso: chest and pelvis when they are separate bodies; hand: the
#: wrist keypoint's body and below, up to 6 bodies: a gripper's fingers and motors, whose smaller
#: links went 5 mm into Talos' thigh when only the 2 largest were kept).
LIMB_BODIES = {"leg": 5, "arm": 2, "torso": 2, "hand": 6}
#: Cap (m) on how much closer than at the nominal posture an allowance lets a pair come (see CapsulePair).
NOMINAL_CLEARANCE = 0.02
#: A box whose long half-extent is this many times its cross half-extent is "elongated".
ELONGATED = 1.5
#: Extra clearance (m) kept between capsules (box corners stick out of their capsule a little).
MARGIN = 0.003
_ROUND = {int(mujoco.mjtGeom.mjGEOM_CAPSULE), int(mujoco.mjtGeom.mjGEOM_SPHERE), int(mujoco.mjtGeom.mjGEOM_CYLINDER)}


@dataclass(frozen=True, eq=False)
class BodyCapsule:
    """Segment end points ``p0``, ``p1`` (m, in body ``body``'s frame) and ``radius`` (m)."""

    body: int
    p0: np.ndarray
    p1: np.ndarray
    radius: float


@dataclass(frozen=True, eq=False)
class CapsulePair:
    """Two capsules, or a capsule and a body's polytope, to keep apart; ``allowance`` (m) is
    subtracted from their radii: what the two capsules provably overstate their bodies' geometry
    by (:func:`overstatement`), for pairs the nominal posture holds closer than
    :data:`NOMINAL_CLEARANCE`."""

    name: str
    a: BodyCapsule
    b: BodyCapsule | BodyPolytope
    allowance: float = 0.0


def _geom_box(m: mujoco.MjModel, g: int) -> tuple[np.ndarray, np.ndarray]:
    """The geom's bounding box in its body's frame: (low corner, high corner)."""
    rot = quat_to_mat_np(m.geom_quat[g])
    centre, half = m.geom_aabb[g, :3], m.geom_aabb[g, 3:]
    corners = centre + half * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    pts = m.geom_pos[g] + corners @ rot.T
    return pts.min(axis=0), pts.max(axis=0)


def _mesh_vertices(m: mujoco.MjModel, g: int) -> np.ndarray | None:
    """A mesh geom's vertices in its body's frame (m; those of its convex hull when MuJoCo built
    one), or None for other geom types."""
    if int(m.geom_type[g]) != int(mujoco.mjtGeom.mjGEOM_MESH) or m.geom_dataid[g] < 0:
        return None
    mesh = int(m.geom_dataid[g])
    start, count = int(m.mesh_vertadr[mesh]), int(m.mesh_vertnum[mesh])
    verts = m.mesh_vert[start:start + count]
    adr = int(m.mesh_graphadr[mesh])
    if adr >= 0:  # MuJoCo's convex hull of the mesh: its vertices are all a capsule must hold
        nv = int(m.mesh_graph[adr])
        verts = verts[m.mesh_graph[adr + 2 + nv:adr + 2 + 2 * nv]]
    return m.geom_pos[g] + verts @ quat_to_mat_np(m.geom_quat[g]).T


def collision_geoms(m: mujoco.MjModel) -> dict[int, list[int]]:
    """Each body's collision geoms (contype or conaffinity set; the world body's left out)."""
    out: dict[int, list[int]] = {}
    for g in range(m.ngeom):
        if (m.geom_contype[g] or m.geom_conaffinity[g]) and m.geom_bodyid[g] != 0:
            out.setdefault(int(m.geom_bodyid[g]), []).append(g)
    return out


#: Geom types whose bounding-box capsule need not hold them.
_FLAT = {int(mujoco.mjtGeom.mjGEOM_CYLINDER), int(mujoco.mjtGeom.mjGEOM_ELLIPSOID)}
#: Points per circle of :func:`_geom_points`.
_RIM = 72


def _fibonacci(n: int) -> np.ndarray:
    """n roughly even unit vectors."""
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    phi = np.pi * (1 + 5 ** 0.5) * i
    rho = np.sqrt(1 - z * z)
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1)


def _geom_points(m: mujoco.MjModel, g: int) -> np.ndarray:
    """Points in the body frame whose convex hull holds geom ``g``: a mesh's vertices, a box's
    corners, a cylinder's two rims as circumscribed 72-gons; spheres, capsule ends and ellipsoids
    as 400 directions pushed out by 3 % (the largest gap between those directions is ~0.2 rad, whose
    circumscribing factor 1/cos(0.1) is 1.005)."""
    mesh = _mesh_vertices(m, g)
    if mesh is not None:
        return mesh
    size, t = m.geom_size[g], int(m.geom_type[g])
    ang = np.linspace(0, 2 * np.pi, _RIM, endpoint=False)
    ring = np.stack([np.cos(ang), np.sin(ang), np.zeros(_RIM)], axis=1) / np.cos(np.pi / _RIM)
    ball = 1.03 * _fibonacci(400)
    if t == mujoco.mjtGeom.mjGEOM_BOX:
        local = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * size
    elif t == mujoco.mjtGeom.mjGEOM_CYLINDER:
        local = np.concatenate([size[0] * ring + [0, 0, h] for h in (-size[1], size[1])])
    elif t == mujoco.mjtGeom.mjGEOM_CAPSULE:
        local = np.concatenate([size[0] * ball + [0, 0, h] for h in (-size[1], size[1])])
    elif t == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        local = ball * size
    else:  # sphere; anything else by its bounding sphere
        local = ball * (size[0] if t == mujoco.mjtGeom.mjGEOM_SPHERE else float(m.geom_rbound[g]))
    return m.geom_pos[g] + local @ quat_to_mat_np(m.geom_quat[g]).T


def body_capsules(m: mujoco.MjModel, contain: bool = False) -> dict[int, BodyCapsule]:
    """Each body's capsule: along the longest axis of the union of its collision geoms' bounding
    boxes (body frame), radius the larger cross half-extent; with ``contain``, boxes and meshes get the
    capsule over their whole length with the cross half-diagonal as radius (it holds the corners),
    and bodies whose collision geoms are all meshes the capsule fitted to their vertices
    (:func:`~motion2robot.retarget.capsule_fit.fit_capsule`), as are bodies with a cylinder or an
    ellipsoid (on points of their geoms whose hull holds them, :func:`_geom_points`: the
    bounding-box capsule of a flat cylinder, a sphere, cut its rim: Unitree H1's hip-yaw links
    went 13 mm into each other)."""
    out = {}
    for b, geoms in collision_geoms(m).items():
        bs = [_geom_box(m, g) for g in geoms]
        verts = [_mesh_vertices(m, g) for g in geoms]
        rounded = all(int(m.geom_type[g]) in _ROUND for g in geoms)
        if contain and all(v is not None for v in verts):  # meshes only: fitted to their vertices
            p0, p1, r = fit_capsule(np.concatenate(verts))
            out[b] = BodyCapsule(b, p0, p1, r)
            continue
        if contain and any(int(m.geom_type[g]) in _FLAT for g in geoms):
            # a cylinder or ellipsoid: the bounding-box capsule may cut its rim
            p0, p1, r = fit_capsule(np.concatenate([_geom_points(m, g) for g in geoms]))
            out[b] = BodyCapsule(b, p0, p1, r)
            continue
        lo = np.min([x[0] for x in bs], axis=0)
        hi = np.max([x[1] for x in bs], axis=0)
        centre, half = (lo + hi) / 2, (hi - lo) / 2
        i = int(np.argmax(half))
        radius = float(np.max(np.delete(half, i)))
        # chunky bodies: the inscribed-length capsule; elongated ones (a sole, a limb's capsule
        # geom): a capsule over the whole bounding-box length (for a capsule geom, longer than
        # it by its radius at each end: on the safe side)
        long = half[i] >= ELONGATED * radius
        if contain and not rounded:  # boxes/meshes: a capsule containing the box's corners
            radius, long = float(np.linalg.norm(np.delete(half, i))), True
        axis = np.eye(3)[i] * (float(half[i]) if long else max(float(half[i]) - radius, 0.0))
        out[b] = BodyCapsule(b, centre - axis, centre + axis, radius)
    return out


def overstatement(m: mujoco.MjModel, cap: BodyCapsule) -> float:
    """How much (m) the capsule's radius exceeds the farthest point of its body's collision geoms
    from its segment: the margin by which it overstates that geometry in every direction (0 for a
    capsule fitted to it; negative for an inscribed one, which does not hold it)."""
    pts = np.concatenate([_geom_points(m, g) for g in collision_geoms(m)[cap.body]])
    axis = cap.p1 - cap.p0
    t = np.clip((pts - cap.p0) @ axis / max(float(axis @ axis), 1e-24), 0.0, 1.0)
    return cap.radius - float(np.linalg.norm(pts - cap.p0 - t[:, None] * axis, axis=1).max())


def body_polytopes(m: mujoco.MjModel) -> dict[int, BodyPolytope]:
    """Each body's 14-DOP around its collision geoms (:mod:`~motion2robot.retarget.polytope`)."""
    return {b: body_polytope(m, b, [(g, _mesh_vertices(m, g)) for g in gs]) for b, gs in collision_geoms(m).items()}


def _chain(m: mujoco.MjModel, body: int, stop: set[int]) -> list[int]:
    out = []
    while body > 0 and body not in stop:
        out.append(body)
        body = int(m.body_parentid[body])
    return out


def _limbs(robot: Robot) -> dict[str, list[int]]:
    m = robot.model
    torso = {robot.root_body, robot.torso_body, *_chain(m, robot.torso_body, {robot.root_body})}
    limbs = {"torso": sorted(torso)}
    for side, foot in zip(("left", "right"), robot.foot_bodies):
        limbs[f"{side}_leg"] = _chain(m, int(foot), torso)
        for k in (f"{side}_wrist", f"{side}_elbow"):
            if k in robot.keypoints:
                body = int(m.site_bodyid[robot.keypoint_sites[robot.keypoints.index(k)]])
                chain = _chain(m, body, torso)
                limbs[f"{side}_arm"] = _subtree(m, chain[-1]) if chain else []
                limbs[f"{side}_hand"] = _subtree(m, body)  # the wrist (or elbow) body and below
                break
    return limbs


def _subtree(m: mujoco.MjModel, root: int) -> list[int]:
    """``root`` and its descendants, children before parents (distal first)."""
    out = [b for b in range(1, m.nbody) if _descends(m, b, root)]
    return sorted(out, reverse=True)


def _descends(m: mujoco.MjModel, body: int, root: int) -> bool:
    while body > 0:
        if body == root:
            return True
        body = int(m.body_parentid[body])
    return False


def _largest(bodies: list[int], caps: dict[int, BodyCapsule], k: int) -> list[int]:
    """The ``k`` bodies with the longest capsules (length + diameter), kept in chain order."""
    size = {b: float(np.linalg.norm(caps[b].p1 - caps[b].p0) + 2 * caps[b].radius) for b in bodies if b in caps}
    keep = set(sorted(size, key=size.get, reverse=True)[:k])
    return [b for b in bodies if b in keep]


def _gap_np(pa: tuple[np.ndarray, np.ndarray], pb: tuple[np.ndarray, np.ndarray]) -> float:
    """Distance (m) between two segments given as numpy end points."""
    s, t = (float(x) for x in closest_parameters(*(ca.DM(x) for x in (*pa, *pb))))
    return float(np.linalg.norm(pa[0] + s * (pa[1] - pa[0]) - pb[0] - t * (pb[1] - pb[0])))


def collision_pairs(robot: Robot) -> tuple[CapsulePair, ...]:
    """Capsule pairs to keep apart (see the module docstring)."""
    m = robot.model
    caps = body_capsules(m)
    outer = body_capsules(m, contain=True)
    polys = body_polytopes(m)
    whole = _limbs(robot)
    chunky = set(whole["torso"])  # bodies that may be modelled by their polytope
    limbs = {k: _largest(v, caps, LIMB_BODIES.get(k.split("_")[-1], 1)) for k, v in whole.items()}
    groups = [("left_leg", "right_leg")]
    for side, other in (("left", "right"), ("right", "left")):
        if f"{side}_arm" in limbs:
            limbs[f"{side}_whole_leg"] = whole[f"{side}_leg"]
            limbs[f"{side}_whole_arm"] = whole[f"{side}_arm"]
            groups += [(f"{side}_whole_arm", "torso"), (f"{side}_hand", f"{side}_whole_leg"),
                       (f"{side}_hand", f"{other}_leg")]
    if "left_arm" in limbs and "right_arm" in limbs:
        groups += [("left_arm", "right_arm"), ("left_hand", "right_hand"), ("left_hand", "right_arm"),
                   ("left_arm", "right_hand")]
    d = robot.new_data()

    def world(c: BodyCapsule):
        r, p = d.xmat[c.body].reshape(3, 3), d.xpos[c.body]
        return p + r @ c.p0, p + r @ c.p1

    def _clearance(x: BodyCapsule, y: BodyCapsule | BodyPolytope) -> float:
        """Clearance (m) at the nominal posture, less MARGIN."""
        if isinstance(y, BodyPolytope):
            return clearance_np(y, (d.xpos[y.body], d.xmat[y.body].reshape(3, 3)), *world(x), x.radius) - MARGIN
        return _gap_np(world(x), world(y)) - x.radius - y.radius - MARGIN

    tested = tested_body_pairs(m)  # the pairs MuJoCo tests: no others are kept apart
    out = []
    seen: set[tuple[int, int]] = set()
    for ga, gb in groups:
        for a in limbs.get(ga, []):
            for b in limbs.get(gb, []):
                if a not in caps or b not in caps or (min(a, b), max(a, b)) not in tested \
                        or (min(a, b), max(a, b)) in seen:
                    continue
                seen.add((min(a, b), max(a, b)))
                # the tightest containing model (both capsules, or the thinner body's capsule and
                # the other's polytope); the inscribed capsules if all touch at the nominal posture
                options = [(outer[a], outer[b])]
                options += [(outer[x], polys[y]) for x, y in ((a, b), (b, a)) if y in chunky]
                clearance, ca_, cb = max(((_clearance(x, y), x, y) for x, y in options), key=lambda o: o[0])
                if clearance <= 0:
                    ca_, cb = caps[a], caps[b]
                    clearance = _clearance(ca_, cb)
                if clearance <= 0:
                    continue  # touching at the nominal posture: by design
                name = f"{mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, a)}-{mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b)}"
                # polytopes hug their body (no allowance: it let G1's upper arm 11 mm into the torso);
                # capsules come closer only by what they provably overstate (module docstring)
                allowance = 0.0 if isinstance(cb, BodyPolytope) else \
                    max(0.0, min(NOMINAL_CLEARANCE - clearance, overstatement(m, ca_) + overstatement(m, cb)))
                out.append(CapsulePair(name, ca_, cb, allowance))
    return tuple(out)


def _clamp01(x):
    return ca.fmin(1, ca.fmax(0, x))


def closest_parameters(p1, q1, p2, q2):
    """Parameters (s, t) in [0, 1] of the closest points p1 + s (q1 - p1), p2 + t (q2 - p2) of two
    segments (casadi SX or DM 3-vectors): Ericson, Real-Time Collision Detection, 5.1.9,
    branch-free (if_else)."""
    eps, tiny = 1e-12, 1e-10  # tiny: squared length (m^2) below which a segment is a point
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e, f = ca.dot(d1, d1) + eps, ca.dot(d2, d2) + eps, ca.dot(d2, r)
    c, b = ca.dot(d1, r), ca.dot(d1, d2)
    s = _clamp01((b * f - c * e) / ca.fmax(a * e - b * b, eps))
    s = ca.if_else(e <= tiny, _clamp01(-c / a), ca.if_else(a <= tiny, 0, s))
    t = (b * s + f) / e
    s = ca.if_else(t < 0, _clamp01(-c / a), ca.if_else(t > 1, _clamp01((b - c) / a), s))
    return s, _clamp01(t)


def pair_gap(pair: CapsulePair, ends, ends_now=None, frame=None):
    """Symbolic clearance (m) of a capsule pair minus :data:`MARGIN` (negative = too close): a
    scalar, or for a polytope pair a column with one row per covering sphere.

    ``ends(capsule)`` gives a capsule's two world end points (casadi 3-vectors). With
    ``ends_now`` (the same at the current iterate, without the step) the closest-point parameters
    are taken from those: constants of differentiation (by the envelope theorem their derivative
    does not change the distance's), which keeps the Jacobian as cheap as two points'.
    ``frame(body)``: the body's world position and three axis vectors, for polytope pairs."""
    if isinstance(pair.b, BodyPolytope):
        a0, a1 = ends(pair.a)
        length = float(np.linalg.norm(pair.a.p1 - pair.a.p0))
        gap = clearance_sx(pair.b, *frame(pair.b.body), a0, a1, length, pair.a.radius)
        return gap - MARGIN + pair.allowance
    a0, a1 = ends(pair.a)
    b0, b1 = ends(pair.b)
    ref = ends if ends_now is None else ends_now
    s, t = closest_parameters(*ref(pair.a), *ref(pair.b))
    dist = ca.sqrt(ca.sumsqr(a0 + s * (a1 - a0) - b0 - t * (b1 - b0)) + 1e-12)
    return dist - pair.a.radius - pair.b.radius - MARGIN + pair.allowance

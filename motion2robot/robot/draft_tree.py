"""Find a humanoid's skeleton in an MJCF's kinematic tree (see :mod:`motion2robot.robot.draft`)."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from motion2robot.errors import RobotConfigError
from motion2robot.robot import body_geometry as geo
from motion2robot.robot.draft_joints import clear_arms, draft_joints, draft_nominal, spread_feet, stiffen_ankles
from motion2robot.robot.draft_limb import MEET_TOL, group_joints, pick_shoulder_elbow_wrist
from motion2robot.robot.draft_types import Draft, FootDraft, KeypointDraft, rounded

_HINGE = mujoco.mjtJoint.mjJNT_HINGE
_FREE = mujoco.mjtJoint.mjJNT_FREE


class Skeleton:
    """The model's kinematic tree at qpos0 (world frame, z up) and the guesses made on it:
    ``guesses`` (what was inferred) and ``checks`` (what needs a human look)."""

    def __init__(self, m: mujoco.MjModel, d: mujoco.MjData, where: str):
        self.m, self.d, self.where = m, d, where
        self.guesses: list[str] = []
        self.checks: list[str] = []
        free = [j for j in range(m.njnt) if m.jnt_type[j] == _FREE]
        if len(free) != 1 or free[0] != 0:
            raise RobotConfigError(f"{where}: a humanoid needs exactly one free joint, first in the model, on its pelvis "
                                   f"(found {len(free)}); add <freejoint/> to the root body")
        other = [j for j in range(1, m.njnt) if m.jnt_type[j] != _HINGE]
        if other:
            raise RobotConfigError(f"{where}: joint {self.jname(other[0])} is not a hinge; motion2robot supports a free root plus hinges only")
        self.root = int(m.jnt_bodyid[0])
        self.children: dict[int, list[int]] = {b: [] for b in range(m.nbody)}
        for b in range(1, m.nbody):
            self.children[int(m.body_parentid[b])].append(b)

    # -- small helpers ---------------------------------------------------------------------
    def bname(self, b: int) -> str:
        return mujoco.mj_id2name(self.m, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}"

    def jname(self, j: int) -> str:
        return mujoco.mj_id2name(self.m, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"

    def path(self, b: int) -> list[int]:
        """Bodies from just below the root down to ``b``."""
        out = []
        while b != self.root and b != 0:
            out.append(b)
            b = int(self.m.body_parentid[b])
        return out[::-1]

    def side(self, b: int) -> float:
        return float(geo.to_body(self.d, self.root, self.d.xpos[b])[1])

    def has_hinge(self, b: int) -> bool:
        return any(self.m.jnt_bodyid[j] == b and self.m.jnt_type[j] == _HINGE for j in range(self.m.njnt))

    def named(self, bodies: list[int], *words: str) -> list[int]:
        return [b for b in bodies if any(w in self.bname(b).lower() for w in words)]

    def subtree(self, b: int) -> list[int]:
        out, todo = [], [b]
        while todo:
            x = todo.pop()
            out.append(x)
            todo.extend(self.children[x])
        return out

    def center_of(self, bodies: list[int], candidates: list[int]) -> tuple[int, np.ndarray]:
        """Meeting point of the hinge axes on ``bodies``, attached to the nearest of ``candidates``
        (ties within 1 mm go to the later one). Returns (body, offset in its frame)."""
        pts, dirs, _ = geo.hinge_axes(self.m, self.d, bodies)
        prior = np.mean([self.d.xpos[b] for b in bodies], axis=0)
        c = geo.axes_center(pts, dirs, prior) if len(pts) else self.d.xpos[bodies[-1]].copy()
        dist = [np.linalg.norm(self.d.xpos[b] - c) for b in candidates]
        best = min(dist)
        body = [b for b, x in zip(candidates, dist) if x <= best + 1e-3][-1]
        return body, geo.to_body(self.d, body, c)

    def kp(self, human: str, body: int, offset=(0.0, 0.0, 0.0), weight: float = 1.0, note: str = "") -> KeypointDraft:
        return KeypointDraft(human, self.bname(body), rounded(offset), weight, note)

    # -- the guesses ------------------------------------------------------------------------
    def draft(self, name: str, ref: str, mjcf: Path, menagerie: str | None, entry: str | None) -> Draft:
        leaves = [b for b in self.subtree(self.root) if not self.children[b]]
        feet = {s: self._foot(s, leaves) for s in ("left", "right")}
        split = self._lca(feet["left"], feet["right"])
        legs = {s: self._leg(s, feet[s], split) for s in ("left", "right")}
        leg_bodies = set(sum((self.subtree(legs[s]["chain"][0]) for s in legs), []))
        upper = [b for b in leaves if b not in leg_bodies]
        sides = {s: [b for b in upper if (1.0 if s == "left" else -1.0) * self.side(b) > 0.03] for s in ("left", "right")}
        kps = [self._pelvis(legs)]
        for s in ("left", "right"):
            kps += legs[s]["kps"]
        if all(sides.values()):
            arms = {s: self._arm(s, sides[s]) for s in ("left", "right")}
            torso = self._lca(arms["left"]["leaf"], arms["right"]["leaf"])
            named_torso = self.named(self.path(torso) or [self.root], "torso", "chest")
            self.guesses.append(f"torso body: {self.bname(torso)} (where the arms branch"
                                + ("" if not named_torso or named_torso[-1] == torso else f"; named torso: {self.bname(named_torso[-1])}") + ")")
            kps += self._trunk(torso, arms, legs, leg_bodies)
            for s in ("left", "right"):
                kps += arms[s]["kps"]
        else:
            arms, torso = {}, self.root
            self.guesses.append(f"legs-only robot: no arm on the {' or the '.join(s for s in sides if not sides[s])}; "
                                f"torso body: the root {self.bname(self.root)}; upper-body keypoints left out")
            named = self.named([b for b in self.subtree(self.root) if b not in leg_bodies], "head")
            if named:
                kps.append(self.kp("head", named[-1], weight=0.5, note="head: body named head; its origin"))
        joints, dv, dt, dk = draft_joints(self)
        joints = stiffen_ankles(self, legs, joints)
        nominal = draft_nominal(self, legs, {j.name: j for j in joints})
        nominal = clear_arms(self, arms, {j.name: j for j in joints}, nominal)
        nominal = spread_feet(self, legs, {j.name: j for j in joints}, nominal)
        return Draft(
            name=name, model_ref=ref, mjcf=mjcf, menagerie=menagerie, entry=entry,
            root_body=self.bname(self.root), torso_body=self.bname(torso),
            default_velocity=dv, default_torque=dt, default_kp=dk, joints=tuple(joints), nominal=nominal,
            keypoints=tuple(kps), feet=(legs["left"]["foot"], legs["right"]["foot"]),
            guesses=tuple(self.guesses), checks=tuple(self.checks),
        )

    def _foot(self, side: str, leaves: list[int]) -> int:
        sign = 1.0 if side == "left" else -1.0
        cands = [b for b in leaves if sign * self.side(b) > 0.005]
        root_z = self.d.xpos[self.root][2]
        cands = [b for b in cands if self.d.xpos[b][2] < root_z - 0.05]
        if not cands:
            raise RobotConfigError(f"{self.where}: cannot find a {side} foot (no body 5 cm or more below the root body "
                                   f"{self.bname(self.root)} on the {side}, y {'>' if sign > 0 else '<'} 0, at qpos0); "
                                   "a humanoid must stand along z with x forward and y to its left, both legs below its root body")
        low = min(cands, key=lambda b: self.d.xpos[b][2])
        foot = low
        while foot not in (self.root, 0) and not geo.body_geoms(self.m, foot):
            foot = int(self.m.body_parentid[foot])
        if foot in (self.root, 0):
            raise RobotConfigError(f"{self.where}: the {side} foot {self.bname(low)} and the leg above it have no collision "
                                   "geometry to stand on; add a collision geom (e.g. a box) for the sole to the foot body")
        if foot != low:
            self.guesses.append(f"{side} foot: {self.bname(low)} has no collision geometry; its nearest ancestor with some, "
                                f"{self.bname(foot)}, is the foot")
        return foot

    def _pelvis(self, legs: dict) -> KeypointDraft:
        """The pelvis keypoint at the midpoint of the two hip centres, on the root body."""
        hips = []
        for s in ("left", "right"):
            k = legs[s]["kps"][0]
            b = mujoco.mj_name2id(self.m, mujoco.mjtObj.mjOBJ_BODY, k.body)
            hips.append(self.d.xpos[b] + self.d.xmat[b].reshape(3, 3) @ np.array(k.offset))
        mid = (hips[0] + hips[1]) / 2
        return self.kp("pelvis", self.root, geo.to_body(self.d, self.root, mid),
                       note=f"midpoint of the hip centres, {1000 * np.linalg.norm(mid - self.d.xpos[self.root]):.0f} mm from "
                            f"the root body's origin")

    def _leg(self, side: str, foot: int, split: int) -> dict:
        """The leg from below ``split`` (where the two legs part) down to ``foot``."""
        chain = self.path(foot)
        chain = chain[chain.index(split) + 1:] if split in chain else chain
        nm = self.bname(foot).lower()
        other = "right" if side == "left" else "left"
        if other in nm or nm.startswith(other[0] + "_"):
            self.checks.append(f"{side} foot {self.bname(foot)} is named like the {other} one: check the model's y axis points left")
        knee, how = self._middle(chain, "knee")
        self.guesses.append(f"{side} leg: {' > '.join(self.bname(b) for b in chain)}; knee {self.bname(knee)} ({how})")
        k = chain.index(knee)
        above = [b for b in chain[:k] if self.has_hinge(b)] or chain[:1]
        hip, hip_off = self.center_of(above, chain[:k] or chain[:1])
        below = [b for b in chain[k + 1:] if self.has_hinge(b)]
        if below:
            ankle, ankle_off = self.center_of(below, chain[k + 1:])
        else:
            ankle, ankle_off = foot, np.zeros(3)
            self.checks.append(f"{side} leg has no ankle joint below the knee: ankle keypoint put at {self.bname(foot)}")
        foot_draft = self._sole(side, foot)
        cx, cy, cz = foot_draft.sole_center
        hx = foot_draft.sole_half[0]
        ankle_w = self.d.xpos[ankle] + self.d.xmat[ankle].reshape(3, 3) @ ankle_off
        ankle_h = float(geo.to_body(self.d, foot, ankle_w)[2] - cz)
        ball = (cx + 0.5 * hx, cy, cz + 0.4 * max(ankle_h, 0.0))
        jn = lambda bodies: ", ".join(self.jname(j) for j in geo.hinge_axes(self.m, self.d, bodies)[2])  # noqa: E731
        kps = [self.kp(f"{side}_hip", hip, hip_off, note=f"hip: where the axes of {jn(above)} meet"),
               self.kp(f"{side}_knee", knee, note=f"knee: origin of {self.bname(knee)} ({how})"),
               self.kp(f"{side}_ankle", ankle, ankle_off,
                       note=f"ankle: where the axes of {jn(below)} meet" if below else "CHECK: no ankle joint; the foot body"),
               self.kp(f"{side}_foot", foot, ball, 0.5, "ball of the foot: 3/4 along the sole, 40% of the ankle height up")]
        return {"chain": chain, "foot": foot_draft, "kps": kps, "hip": above, "knee": knee, "ankle": below}

    def _middle(self, chain: list[int], word: str) -> tuple[int, str]:
        named = [b for b in self.named(chain, word) if self.has_hinge(b)]
        if named:
            return named[0], "by name"
        hinged = [b for b in chain if self.has_hinge(b)]
        if len(hinged) < 2:
            raise RobotConfigError(f"{self.where}: the chain {' > '.join(self.bname(b) for b in chain)} has fewer than two hinges; cannot find a {word}")
        length = np.cumsum([0.0] + [np.linalg.norm(self.d.xpos[b] - self.d.xpos[a]) for a, b in zip(chain, chain[1:])])
        tip = length[-1] + self._reach(chain[-1])
        best = min(hinged[1:], key=lambda b: abs(length[chain.index(b)] - tip / 2))
        self.checks.append(f"{word} {self.bname(best)} chosen by position (halfway along {self.bname(chain[0])} > {self.bname(chain[-1])}); no body is named '{word}'")
        return best, "halfway along the chain, CHECK"

    def _reach(self, body: int) -> float:
        """How far the body's geometry reaches beyond its origin (m)."""
        gs = geo.body_geoms(self.m, body) or geo.body_geoms(self.m, body, collision_only=False)
        if not gs:
            return 0.0
        pts = np.concatenate([geo.aabb_corners(self.m, self.d, g) for g in gs])
        return float(np.max(np.linalg.norm(pts - self.d.xpos[body], axis=1)))

    def _sole(self, side: str, foot: int) -> FootDraft:
        bodies = self.subtree(foot)
        gs = sum((geo.body_geoms(self.m, b) for b in bodies), [])
        note = ""
        if not gs:
            gs = sum((geo.body_geoms(self.m, b, collision_only=False) for b in bodies), [])
            note = "CHECK: the foot has no collision geoms; rectangle from its visual geoms"
            self.checks.append(f"{side} sole: {self.bname(foot)} has no collision geoms; the sole came from visual geoms")
        if not gs:
            raise RobotConfigError(f"{self.where}: foot body {self.bname(foot)} has no geoms; cannot find the sole")
        centre, half, npts, frame = geo.sole_rectangle(self.m, self.d, foot, gs)
        quat = geo.mat_to_quat(frame)
        tilted = float(np.degrees(np.arccos(np.clip(frame[2, 2], -1, 1))))
        if tilted > 0.05:
            self.guesses.append(f"{side} foot frame {self.bname(foot)} is tilted {tilted:.1f} deg from the floor at qpos0: "
                                "the sole rectangle is laid in the floor plane (sole_quat)")
        if min(half) < 0.005:
            half = np.maximum(half, 0.01)
            note = "CHECK: sole too narrow in the model's geometry; widened to 2 cm"
            self.checks.append(f"{side} sole: the lowest geometry of {self.bname(foot)} is a point or line; sole widened to 2 cm")
        self.guesses.append(f"{side} sole: {self.bname(foot)}, {2 * half[0]:.3f} x {2 * half[1]:.3f} m at z {centre[2]:+.4f} in its frame ({npts} lowest points)")
        return FootDraft(side, self.bname(foot), rounded(centre), rounded(half),
                         note or f"covers the lowest {npts} points of the foot's collision geometry",
                         None if np.allclose(quat, [1, 0, 0, 0], atol=1e-6) else rounded(quat, 6))

    def _arm(self, side: str, cands: list[int]) -> dict:
        """The arm on ``side``: the leaf among ``cands`` (leaves outside the legs on that side) farthest along the tree."""

        def length(b: int) -> float:
            p = [self.root] + self.path(b)
            return float(sum(np.linalg.norm(self.d.xpos[y] - self.d.xpos[x]) for x, y in zip(p, p[1:])))

        leaf = max(cands, key=length)
        return {"leaf": leaf, "side": side}

    def _cut_hand(self, chain: list[int]) -> tuple[list[int], str]:
        """The arm chain up to the first body where it branches into several jointed parts (a hand
        or gripper: its fingers), which is kept; the reason in words."""
        def jointed(b: int) -> bool:
            return any(self.has_hinge(x) for x in self.subtree(b))
        for i, b in enumerate(chain):
            if sum(1 for c in self.children[b] if jointed(c)) >= 2:
                return chain[: i + 1], f"; hand/gripper from {self.bname(b)} on (it branches into fingers)"
        return chain, ""

    def _arm_keypoints(self, arm: dict, torso: int) -> list[KeypointDraft]:
        side, leaf = arm["side"], arm["leaf"]
        full = self.path(leaf)
        chain = full[full.index(torso) + 1:] if torso in full else full
        chain, hand = self._cut_hand(chain)
        pts, dirs, jids = geo.hinge_axes(self.m, self.d, chain)
        groups = group_joints(pts, dirs)
        if len(groups) < 2:
            raise RobotConfigError(f"{self.where}: the {side} arm {' > '.join(self.bname(b) for b in chain)} has no elbow "
                                   "(its hinge axes all meet in one point); map the arm keypoints by hand in the TOML")
        s, e, w = pick_shoulder_elbow_wrist(groups)
        sh = [jids[k] for k in groups[s].joints]
        arm["roll"] = max(sh, key=lambda j: abs(self.d.xaxis[j][0]))  # abducts the arm: axis along x
        arm["bodies"] = self.subtree(chain[0])
        names = lambda g: ", ".join(self.jname(jids[k]) for k in groups[g].joints)  # noqa: E731

        def body_of(g: int) -> int:  # the group's body nearest to where its axes meet (ties: the later)
            bodies = [int(self.m.jnt_bodyid[jids[k]]) for k in groups[g].joints]
            dist = [float(np.linalg.norm(self.d.xpos[b] - groups[g].centre)) for b in bodies]
            return [b for b, x in zip(bodies, dist) if x <= min(dist) + 1e-3][-1]
        self.guesses.append(f"{side} arm: {' > '.join(self.bname(b) for b in chain)}{hand}")
        out = []
        for human, g, what in ((f"{side}_shoulder", s, "shoulder"), (f"{side}_elbow", e, "elbow")):
            b = body_of(g)
            out.append(self.kp(human, b, geo.to_body(self.d, b, groups[g].centre),
                               note=f"{what}: where the axes of {names(g)} meet"))
        if w is not None:
            b = body_of(w)
            out.append(self.kp(f"{side}_wrist", b, geo.to_body(self.d, b, groups[w].centre),
                               note=f"wrist: where the axes of {names(w)} meet (the last arm joints before the hand)"))
            return out
        ec = groups[e].centre
        twist = [k for k in groups[e].joints[1:] if np.linalg.norm(pts[k] - ec) > MEET_TOL]
        if twist:
            k = twist[-1]
            b = int(self.m.jnt_bodyid[jids[k]])
            out.append(self.kp(f"{side}_wrist", b, geo.to_body(self.d, b, pts[k]),
                               note=f"wrist: the forearm-twist joint {self.jname(jids[k])} where it carries the hand, "
                                    f"{1000 * np.linalg.norm(pts[k] - ec):.0f} mm beyond the elbow"))
            return out
        last = chain[-1]
        off = self._forearm_tip(last)
        out.append(self.kp(f"{side}_wrist", last, off, note="CHECK: no wrist joint; put at 90% of the forearm geometry's reach"))
        self.checks.append(f"{side} wrist: no wrist joint or body; keypoint put at 90% of {self.bname(last)}'s reach {rounded(off, 3)}")
        return out

    def _forearm_tip(self, body: int) -> np.ndarray:
        gs = geo.body_geoms(self.m, body) or geo.body_geoms(self.m, body, collision_only=False)
        if not gs:
            return np.zeros(3)
        far = max(gs, key=lambda g: np.linalg.norm(geo.to_body(self.d, body, self.d.geom_xpos[g])))
        direction = geo.to_body(self.d, body, self.d.geom_xpos[far])
        direction = direction / (np.linalg.norm(direction) or 1.0)
        pts = np.concatenate([geo.aabb_corners(self.m, self.d, g) for g in gs])
        reach = max(float(geo.to_body(self.d, body, p) @ direction) for p in pts)
        return 0.9 * reach * direction

    def _lca(self, a: int, b: int) -> int:
        pa, pb = [self.root] + self.path(a), [self.root] + self.path(b)
        common = [x for x, y in zip(pa, pb) if x == y]
        return common[-1]

    def _trunk(self, torso: int, arms: dict, legs: dict, leg_bodies: set) -> list[KeypointDraft]:
        arm_kps = {s: self._arm_keypoints(arms[s], torso) for s in arms}
        for s in arms:
            arms[s]["kps"] = arm_kps[s]
        world = {}
        for k in arm_kps["left"] + arm_kps["right"] + legs["left"]["kps"] + legs["right"]["kps"]:
            b = mujoco.mj_name2id(self.m, mujoco.mjtObj.mjOBJ_BODY, k.body)
            world[k.human] = self.d.xpos[b] + self.d.xmat[b].reshape(3, 3) @ np.array(k.offset)
        shoulders = (world["left_shoulder"] + world["right_shoulder"]) / 2
        hips = (world["left_hip"] + world["right_hip"]) / 2
        arm_bodies = {b for s in arms for b in self.subtree(self.path(arms[s]["leaf"])[len(self.path(torso))])}
        head_body, head_w, how = self._head(leg_bodies | arm_bodies)
        self.guesses.append(f"head: {self.bname(head_body)} ({how})")
        centre = self.d.xpos[torso].copy()
        spine3 = np.array([shoulders[0], centre[1], shoulders[2] - 0.15 * (shoulders[2] - hips[2])])
        neck = np.array([shoulders[0], centre[1], shoulders[2] + 0.25 * (head_w[2] - shoulders[2])])
        out = [self.kp("spine3", torso, geo.to_body(self.d, torso, spine3), 0.5, "15% of the way from the shoulders down to the hips"),
               self.kp("neck", torso, geo.to_body(self.d, torso, neck), 0.5, "a quarter of the way from the shoulders up to the head"),
               self.kp("head", head_body, geo.to_body(self.d, head_body, head_w), 0.5,
                       f"head: {how}" if "CHECK" not in how else "CHECK: " + how.replace(", CHECK", ""))]
        return out

    def _head(self, exclude: set) -> tuple[int, np.ndarray, str]:
        bodies = [b for b in self.subtree(self.root) if b not in exclude]
        named = self.named(bodies, "head")
        if named:
            b = named[-1]
            gs = geo.body_geoms(self.m, b, collision_only=False)
            if gs:
                pts = np.concatenate([geo.aabb_corners(self.m, self.d, g) for g in gs])
                return b, (pts.min(0) + pts.max(0)) / 2, "body named head; centre of its geometry"
            return b, self.d.xpos[b].copy(), "body named head; its origin"
        for g in range(self.m.ngeom):
            gname = mujoco.mj_id2name(self.m, mujoco.mjtObj.mjOBJ_GEOM, g) or ""
            mesh = self.m.geom_dataid[g]
            mname = (mujoco.mj_id2name(self.m, mujoco.mjtObj.mjOBJ_MESH, mesh) or "") if self.m.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH and mesh >= 0 else ""
            if "head" in gname.lower() or "head" in mname.lower():
                b = int(self.m.geom_bodyid[g])
                if b in bodies:
                    pts = geo.aabb_corners(self.m, self.d, g)
                    return b, (pts.min(0) + pts.max(0)) / 2, f"centre of the geom {'named ' + gname if gname else 'with mesh ' + mname}"
        top = max(bodies, key=lambda b: self.d.xpos[b][2])
        self.checks.append(f"head: nothing is named head; keypoint put at the highest trunk body {self.bname(top)}")
        return top, self.d.xpos[top].copy(), "highest trunk body, CHECK"

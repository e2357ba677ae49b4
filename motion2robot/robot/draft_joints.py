"""Draft joint limits, gains and the nominal posture from an MJCF (see :mod:`motion2robot.robot.draft`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from motion2robot.robot.collision_filter import tested_geom_pairs
from motion2robot.robot.draft_types import JointDraft

if TYPE_CHECKING:  # pragma: no cover
    from motion2robot.robot.draft_tree import Skeleton

DEFAULT_VELOCITY = 5.0  # rad/s, when nothing is known (an MJCF has no velocity limits)
KNEE_BEND = 0.3  # rad, nominal knee flexion
RANGE_GUESS = 1.5  # rad, +- range for joints the model leaves unlimited


def draft_joints(skel: "Skeleton") -> tuple[list[JointDraft], float, float, float]:
    """Per-hinge range (None = the model's), torque and kp, and the [defaults]; ``skel`` is the
    :class:`~motion2robot.robot.draft_tree.Skeleton` (its ``checks`` collect what needs a look)."""
    m = skel.m
    torques: dict[int, float] = {}
    gains: dict[int, float] = {}
    for a in range(m.nu):
        if m.actuator_trntype[a] != mujoco.mjtTrn.mjTRN_JOINT:
            continue
        j = int(m.actuator_trnid[a, 0])
        gear = abs(float(m.actuator_gear[a, 0])) or 1.0
        lim = []
        if m.actuator_forcelimited[a]:
            lim.append(max(abs(m.actuator_forcerange[a])) * gear)
        is_position = m.actuator_biastype[a] == mujoco.mjtBias.mjBIAS_AFFINE and m.actuator_biasprm[a, 1] == -m.actuator_gainprm[a, 0]
        is_motor = m.actuator_biastype[a] == mujoco.mjtBias.mjBIAS_NONE and m.actuator_gaintype[a] == mujoco.mjtGain.mjGAIN_FIXED
        if is_motor and m.actuator_ctrllimited[a]:
            lim.append(max(abs(m.actuator_ctrlrange[a])) * abs(m.actuator_gainprm[a, 0]) * gear)
        if lim:
            torques[j] = min(lim + ([torques[j]] if j in torques else []))
        if is_position:
            gains[j] = float(m.actuator_gainprm[a, 0]) * gear * gear
    for j in range(1, m.njnt):
        if m.jnt_actfrclimited[j]:
            t = max(abs(m.jnt_actfrcrange[j]))
            torques[j] = min(t, torques.get(j, t))
    mass = float(m.body_subtreemass[skel.root])
    default_t = round(max(1.0, mass * 9.81 * 0.1), 1)
    if torques:
        default_t = float(np.median(list(torques.values())))
    else:
        skel.checks.append(f"torque limits: the model has no actuator force range; every joint gets {default_t} N*m "
                           "(weight x 0.1 m): replace with the actuators' datasheet figures")
    skel.checks.append(f"velocity limits: an MJCF has none; every joint gets {DEFAULT_VELOCITY} rad/s: replace with the actuators' datasheet figures")
    out = []
    unlimited, capped = [], []
    for j in range(1, m.njnt):
        name = skel.jname(j)
        rng, notes = None, []
        if not m.jnt_limited[j]:
            rng = (-RANGE_GUESS, RANGE_GUESS)
            unlimited.append(name)
            notes.append("CHECK: the model declares no range; conservative guess")
        t = torques.get(j)
        if t is None:
            t = default_t
            if torques:
                notes.append("CHECK: no actuator force range for this joint; torque is the median of the others")
        kp = gains.get(j, round(t / 0.5, 2))
        if kp > t / 0.05:  # a gain that saturates the torque within 0.05 rad only bangs against the limit
            kp = round(t / 0.05, 2)
            capped.append(name)
            notes.append("CHECK: the model's position gain saturates this joint's torque within 0.05 rad; capped to torque / 0.05 rad")
        else:
            notes.append("kp from the model's position actuator" if j in gains else "kp = torque / 0.5 rad")
        out.append(JointDraft(name, rng, round(float(t), 3), round(float(kp), 3), "; ".join(notes)))
    if unlimited:
        skel.checks.append(f"joint ranges: {len(unlimited)} joints have no range in the model ({', '.join(unlimited[:4])}"
                           f"{', ...' if len(unlimited) > 4 else ''}); drafted as +-{RANGE_GUESS} rad: set the real mechanical ranges")
    if capped:
        skel.checks.append(f"kp: the model's position gain would saturate the torque of {', '.join(capped)} within "
                           "0.05 rad; capped to torque / 0.05 rad")
    kp_default = float(np.median([jd.kp for jd in out])) if out else 20.0
    return out, DEFAULT_VELOCITY, round(default_t, 3), round(kp_default, 3)

def round_inside(v: float, lo: float, hi: float, nd: int = 4) -> float:
    """``v`` rounded to ``nd`` decimals, towards the inside of [lo, hi] where plain rounding would
    leave it (Talos: 0.008727 rounds to 0.0087, below its lower limit)."""
    r, step = round(v, nd), 10.0 ** -nd
    if r < lo:
        r = np.ceil(lo / step) * step
    if r > hi:
        r = np.floor(hi / step) * step
    return round(float(r), nd + 2) + 0.0


def draft_nominal(skel: "Skeleton", legs: dict, joints: dict[str, JointDraft]) -> dict:
    """Zeros (clipped into the ranges) with the knees bent :data:`KNEE_BEND` where the hip, knee and
    ankle pitch joints are found: hip and ankle pitch -KNEE_BEND/2, so pelvis and soles stay level."""
    nominal: dict[str, float] = {}
    m = skel.m

    def bounds(j: int) -> tuple[float, float]:
        jd = joints[skel.jname(j)]
        return jd.range if jd.range else (float(m.jnt_range[j, 0]), float(m.jnt_range[j, 1]))

    def pitch(bodies: list[int]) -> int | None:
        ids = [j for j in range(1, m.njnt) if int(m.jnt_bodyid[j]) in bodies and abs(skel.d.xaxis[j][1]) > 0.9]
        return ids[-1] if ids else None

    for s, leg in legs.items():
        hip, knee, ankle = pitch(leg["hip"]), pitch([leg["knee"]]), pitch(leg["ankle"])
        if None in (hip, knee, ankle):
            skel.checks.append(f"{s} leg: could not find hip, knee and ankle pitch joints; nominal knees left straight")
            continue
        want = {hip: -KNEE_BEND / 2, knee: KNEE_BEND, ankle: -KNEE_BEND / 2}  # rotations about world +y
        q = {j: phi / float(np.sign(skel.d.xaxis[j][1])) for j, phi in want.items()}
        if all(bounds(j)[0] <= v <= bounds(j)[1] for j, v in q.items()):
            nominal.update({skel.jname(j): round_inside(v, *bounds(j)) for j, v in q.items()})
        else:
            skel.checks.append(f"{s} leg: a {KNEE_BEND} rad knee bend is outside the joint ranges; nominal knees left straight")
    for j in range(1, m.njnt):
        lo, hi = bounds(j)
        if not lo <= 0.0 <= hi and skel.jname(j) not in nominal:
            nominal[skel.jname(j)] = round_inside(float(np.clip(0.0, lo, hi)), lo, hi)
    skel.guesses.append("nominal: " + (", ".join(f"{k} = {v:+.3f}" for k, v in nominal.items()) or "all zero")
                        + "; arms as in the model's zero pose")
    return nominal


#: m; the nominal posture keeps each arm this far from the trunk and legs (where its range allows).
ARM_CLEARANCE = 0.03


def clear_arms(skel: "Skeleton", arms: dict, joints: dict[str, JointDraft], nominal: dict, step: float = 0.05,
               most: float = 0.6) -> dict:
    """Abduct each arm (its shoulder joint whose axis runs along x) in ``step`` rad steps, up to
    ``most``, while the bodies below that joint are closer than :data:`ARM_CLEARANCE` to the rest
    of the robot at the nominal posture and abducting helps (Talos' hands rest in its thighs and
    the G1's upper arms touch its torso at qpos0: a retargeter must keep those apart from the
    start). Distances between the geom pairs MuJoCo tests (``mj_geomDistance``)."""
    m = skel.m
    d = mujoco.MjData(m)
    out = dict(nominal)
    tested = tested_geom_pairs(m)
    fromto = np.zeros(6)

    def gap(pairs: list[tuple[int, int]]) -> float:
        d.qpos[:] = m.qpos0
        for j in range(1, m.njnt):
            d.qpos[m.jnt_qposadr[j]] = out.get(skel.jname(j), d.qpos[m.jnt_qposadr[j]])
        mujoco.mj_kinematics(m, d)
        return min((mujoco.mj_geomDistance(m, d, a, b, ARM_CLEARANCE, fromto) for a, b in pairs), default=ARM_CLEARANCE)

    for side, arm in arms.items():
        if "roll" not in arm:
            continue
        j = arm["roll"]
        below = set(skel.subtree(int(m.jnt_bodyid[j]))) - {int(m.jnt_bodyid[j])}
        rest = set(range(1, m.nbody)) - set(arm["bodies"])
        pairs = [(a, b) for a in range(m.ngeom) if int(m.geom_bodyid[a]) in below
                 for b in range(m.ngeom) if int(m.geom_bodyid[b]) in rest and tested[a, b]]
        name = skel.jname(j)
        jd = joints[name]
        lo, hi = jd.range if jd.range else (float(m.jnt_range[j, 0]), float(m.jnt_range[j, 1]))
        sign = (1.0 if side == "left" else -1.0) / float(np.sign(skel.d.xaxis[j][0]))  # outwards
        start = out.get(name, 0.0)
        moved, now = 0.0, gap(pairs)
        while now < ARM_CLEARANCE and moved < most - 1e-9:
            v = start + sign * (moved + step)
            if not lo <= v <= hi:
                break
            out[name] = round_inside(v, lo, hi)
            after = gap(pairs)
            if after <= now + 1e-4:  # abducting does not help
                out[name] = round_inside(start + sign * moved, lo, hi) if moved else start
                break
            moved, now = moved + step, after
        if moved:
            skel.guesses.append(f"{side} arm {1000 * now:.0f} mm from the body at the nominal pose after abducting it: "
                                f"{name} = {out[name]:+.3f}")
    return out


#: m; the nominal stance keeps the feet this far apart (where hip and ankle roll joints allow).
FEET_CLEARANCE = 0.03


def spread_feet(skel: "Skeleton", legs: dict, joints: dict[str, JointDraft], nominal: dict, step: float = 0.005,
                most: float = 0.1) -> dict:
    """Roll both legs outwards at the hips, and the ankles back so the soles stay flat, in ``step``
    rad steps up to ``most``, while the feet are closer than :data:`FEET_CLEARANCE` at the nominal
    posture (the OP3's are 17 mm apart at qpos0, where a retargeter has no room to keep them
    apart). Distances between the geom pairs MuJoCo tests."""
    m = skel.m
    d = mujoco.MjData(m)
    tested = tested_geom_pairs(m)
    fromto = np.zeros(6)

    def roll(bodies: list[int]) -> int | None:
        ids = [j for j in range(1, m.njnt) if int(m.jnt_bodyid[j]) in bodies and abs(skel.d.xaxis[j][0]) > 0.9]
        return ids[0] if ids else None

    hips = {s: roll(leg["hip"]) for s, leg in legs.items()}
    ankles = {s: roll(leg["ankle"]) for s, leg in legs.items()}
    if None in hips.values() or None in ankles.values():
        return nominal
    feet = [set(skel.subtree(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, legs[s]["foot"].body))) for s in ("left", "right")]
    pairs = [(a, b) for a in range(m.ngeom) if int(m.geom_bodyid[a]) in feet[0]
             for b in range(m.ngeom) if int(m.geom_bodyid[b]) in feet[1] and tested[a, b]]

    def posture(a: float) -> dict | None:
        out = dict(nominal)
        for s, sign in (("left", 1.0), ("right", -1.0)):
            for j, phi in ((hips[s], sign * a), (ankles[s], -sign * a)):
                jd = joints[skel.jname(j)]
                lo, hi = jd.range if jd.range else (float(m.jnt_range[j, 0]), float(m.jnt_range[j, 1]))
                v = out.get(skel.jname(j), 0.0) + phi / float(np.sign(skel.d.xaxis[j][0]))
                if not lo <= v <= hi:
                    return None
                out[skel.jname(j)] = round_inside(v, lo, hi)
        return out

    def gap(q: dict) -> float:
        d.qpos[:] = m.qpos0
        for j in range(1, m.njnt):
            d.qpos[m.jnt_qposadr[j]] = q.get(skel.jname(j), d.qpos[m.jnt_qposadr[j]])
        mujoco.mj_kinematics(m, d)
        return min((mujoco.mj_geomDistance(m, d, a, b, FEET_CLEARANCE, fromto) for a, b in pairs), default=FEET_CLEARANCE)

    best, a = nominal, 0.0
    while gap(best) < FEET_CLEARANCE and a < most - 1e-9:
        a += step
        q = posture(a)
        if q is None:
            break
        best = q
    if best is not nominal:
        skel.guesses.append(f"feet {1000 * gap(best):.0f} mm apart at the nominal pose after rolling the legs out "
                            f"{a:.3f} rad at the hips (ankles back, soles flat)")
    return best


def stiffen_ankles(skel: "Skeleton", legs: dict, joints: list[JointDraft]) -> list[JointDraft]:
    """Standing on servos alone, the body pivots on its ankles like an inverted pendulum: each
    ankle joint needs kp > M g h / 2 (M total mass, h CoM height above the ankles at qpos0). Raise
    ankle gains to 1.5 x that (at most torque / 0.05 rad) and say so."""
    m, d = skel.m, skel.d
    mujoco.mj_comPos(m, d)
    bodies = {b for leg in legs.values() for b in leg["ankle"]}
    ids = {j for j in range(1, m.njnt) if int(m.jnt_bodyid[j]) in bodies}
    if not ids:
        return joints
    h = float(d.subtree_com[skel.root][2] - np.mean([d.xanchor[j][2] for j in ids]))
    need = round(1.5 * float(m.body_subtreemass[skel.root]) * 9.81 * h / 2, 1)
    names = {skel.jname(j) for j in ids}
    out, raised = [], []
    for jd in joints:
        if jd.name in names and jd.kp < need:
            kp = min(need, round(jd.torque / 0.05, 2))
            jd = JointDraft(jd.name, jd.range, jd.torque, kp, jd.note + f"; ankle kp raised to hold the body (M g h / 2 = {need / 1.5:.0f})")
            raised.append(jd.name)
        out.append(jd)
    if raised:
        skel.guesses.append(f"ankle kp raised to {need:g} (1.5 x M g h / 2, h = {h:.2f} m) on {', '.join(raised)}")
    return out

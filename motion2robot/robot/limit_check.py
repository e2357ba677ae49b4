"""Self-collision at the joint limits: is every limit reachable from the nominal pose without the
robot's shells running into each other?

Probes (all other joints at the nominal posture, root at the identity):

- **sweeps**: each hinge alone moves from its nominal angle to its lower and to its upper limit;
- **corners**: for every pair of hinges on the same limb (same child subtree of the root body),
  the four corners of their limit box.

At each probe configuration the robot-robot clearance is measured with MuJoCo's collision
detection on a copy of the model whose geoms carry a detection margin, so that near misses are
reported too: the result is the minimum signed distance (metres; negative = penetration) over
all robot geom pairs MuJoCo would collide (parent-child and ``<exclude>`` pairs are skipped as
in simulation). Geoms of the world body (a floor) are ignored. Distances at or above the margin
are reported as the margin.
"""

from __future__ import annotations

import copy
import itertools
from dataclasses import dataclass
from typing import Mapping

import mujoco
import numpy as np

_HINGE = mujoco.mjtJoint.mjJNT_HINGE


@dataclass(frozen=True)
class Probe:
    """One probed configuration (or sweep) and the closest robot-robot approach found.

    kind: "sweep" or "corner"; label: human-readable ("l_knee -> upper 2.3", ...);
    joints: the joint values (rad) that differ from nominal (for a sweep, the end value);
    min_distance: minimum signed distance (m) between robot geoms, capped at the margin;
    worst_at: the joint values (rad) where it occurred; pair: the two geom names (or None).
    """

    kind: str
    label: str
    joints: Mapping[str, float]
    min_distance: float
    worst_at: Mapping[str, float]
    pair: tuple[str, str] | None


def hinge_names(model: mujoco.MjModel) -> list[str]:
    """Names of the model's hinge joints, in model order."""
    return [model.joint(j).name for j in range(model.njnt) if model.jnt_type[j] == _HINGE]


def limbs(model: mujoco.MjModel) -> dict[str, list[str]]:
    """Hinges grouped by limb: the child body of the root body whose subtree holds them.

    Keys are those child bodies' names (e.g. ``l_hip_yaw_link`` for the left leg)."""
    root = int(model.jnt_bodyid[0]) if model.njnt and model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE else 0
    groups: dict[str, list[str]] = {}
    for j in range(model.njnt):
        if model.jnt_type[j] != _HINGE:
            continue
        b = int(model.jnt_bodyid[j])
        while int(model.body_parentid[b]) != root and b != 0:
            b = int(model.body_parentid[b])
        groups.setdefault(model.body(b).name, []).append(model.joint(j).name)
    return groups


class ClearanceProbe:
    """Measures robot-robot clearance at configurations of a model (kept on a private copy)."""

    def __init__(self, model: mujoco.MjModel, margin: float = 0.02) -> None:
        self.model = copy.deepcopy(model)
        self.model.geom_margin[:] = margin
        self.model.geom_gap[:] = 0.0
        self.margin = float(margin)
        self.data = mujoco.MjData(self.model)
        self._robot_geom = self.model.geom_bodyid != 0
        self._qadr = {self.model.joint(j).name: int(self.model.jnt_qposadr[j]) for j in range(self.model.njnt)}

    def qpos(self, values: Mapping[str, float]) -> np.ndarray:
        """A qpos with the root at the identity and the given hinge values (others 0)."""
        q = self.model.qpos0.copy()
        if self.model.njnt and self.model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE:
            q[0:7] = (0, 0, 0, 1, 0, 0, 0)
        for name, v in values.items():
            q[self._qadr[name]] = v
        return q

    def clearance(self, q: np.ndarray) -> tuple[float, tuple[str, str] | None]:
        """Minimum signed distance (m) between robot geoms at ``q`` and the closest geom pair."""
        m, d = self.model, self.data
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_collision(m, d)
        best, pair = self.margin, None
        for c in d.contact[: d.ncon]:
            g1, g2 = int(c.geom1), int(c.geom2)
            if self._robot_geom[g1] and self._robot_geom[g2] and c.dist < best:
                best, pair = float(c.dist), (m.geom(g1).name or f"geom{g1}", m.geom(g2).name or f"geom{g2}")
        return best, pair

    def worst(self, configs: list[dict[str, float]]) -> tuple[float, dict[str, float], tuple[str, str] | None]:
        """The closest approach over ``configs`` (full joint dicts)."""
        best = (np.inf, {}, None)
        for cfg in configs:
            dist, pair = self.clearance(self.qpos(cfg))
            if dist < best[0]:
                best = (dist, cfg, pair)
        return best


def check_limits(
    model: mujoco.MjModel,
    nominal: Mapping[str, float],
    *,
    steps: int = 16,
    margin: float = 0.02,
) -> list[Probe]:
    """Probe every limit sweep and every same-limb limit-box corner of ``model`` (ranges as compiled).

    nominal: joint -> rad (joints absent are 0). steps: samples per sweep (ends included).
    Returns sweeps first (model joint order, lower then upper), then corners."""
    probe = ClearanceProbe(model, margin)
    names = hinge_names(model)
    rng = {n: tuple(float(v) for v in model.joint(n).range) for n in names}
    base = {n: float(nominal.get(n, 0.0)) for n in names}
    out: list[Probe] = []
    for n in names:
        for side, limit in (("lower", rng[n][0]), ("upper", rng[n][1])):
            cfgs = [{**base, n: float(v)} for v in np.linspace(base[n], limit, steps)]
            dist, at, pair = probe.worst(cfgs)
            out.append(Probe("sweep", f"{n} -> {side} {limit:+.3f}", {n: limit}, dist, {n: at[n]}, pair))
    for limb, joints in limbs(model).items():
        for a, b in itertools.combinations(joints, 2):
            for (sa, va), (sb, vb) in itertools.product(zip(("lower", "upper"), rng[a]), zip(("lower", "upper"), rng[b])):
                cfg = {**base, a: va, b: vb}
                dist, pair = probe.clearance(probe.qpos(cfg))
                out.append(Probe("corner", f"{a} {sa} {va:+.3f} & {b} {sb} {vb:+.3f}", {a: va, b: vb}, dist, {a: va, b: vb}, pair))
    return out


def free_extent(
    model: mujoco.MjModel,
    nominal: Mapping[str, float],
    joint: str,
    stop: float,
    *,
    step: float = 0.01,
    tolerance: float = 0.0,
) -> tuple[float, tuple[str, str] | None]:
    """How far ``joint`` can move from its nominal angle towards ``stop`` (rad, absolute) before
    robot geoms come closer than ``tolerance`` (m; 0 = touching). Returns the last clear angle
    (``stop`` if none touched) and the pair that stopped it. Used to choose and justify limits."""
    probe = ClearanceProbe(model, margin=max(0.02, tolerance + 0.01))
    names = hinge_names(model)
    base = {n: float(nominal.get(n, 0.0)) for n in names}
    start = base[joint]
    n_steps = max(1, int(np.ceil(abs(stop - start) / step)))
    last = start
    for v in np.linspace(start, stop, n_steps + 1):
        dist, pair = probe.clearance(probe.qpos({**base, joint: float(v)}))
        if dist < tolerance:
            return last, pair
        last = float(v)
    return float(stop), None

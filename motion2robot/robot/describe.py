"""What a robot is, as data for people: the known robots and their origins, and a robot's joint table.

Pure look-ups (no printing): :mod:`motion2robot.cli.cmd_robots` formats them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from motion2robot.errors import RobotConfigError
from motion2robot.robot.loader import load_robot
from motion2robot.robot.resolve import MENAGERIE_PREFIX, bundled_names, menagerie_available, menagerie_config_names
from motion2robot.robot.robot import Robot


@dataclass(frozen=True)
class RobotEntry:
    """One known robot: ``name`` to pass as ``--robot``, ``origin`` (bundled | menagerie),
    ``available`` (loadable now, offline), ``where`` (how/where it is found), and when it loaded:
    ``dof`` (hinges), ``mass`` (kg), ``height`` (m, highest keypoint at the nominal pose);
    ``error`` holds the one-line reason it did not load."""

    name: str
    origin: str
    available: bool
    where: str
    dof: int | None = None
    mass: float | None = None
    height: float | None = None
    error: str = ""


@dataclass(frozen=True)
class JointRow:
    """One hinge of a robot: limits (rad), velocity (rad/s), torque (N*m), kp (N*m/rad), nominal
    angle (rad), servo ID (None without a servo map) and the config's reason for its range."""

    name: str
    lower: float
    upper: float
    velocity: float
    torque: float
    kp: float
    nominal: float
    servo_id: int | None
    reason: str

    @property
    def lower_deg(self) -> float:
        return math.degrees(self.lower)

    @property
    def upper_deg(self) -> float:
        return math.degrees(self.upper)


def known_robots(load: bool = True) -> list[RobotEntry]:
    """Bundled robots and Menagerie robots with a shipped config, with availability; when ``load``
    is true, each available robot is loaded to report DOF, mass and height."""
    entries = [RobotEntry(n, "bundled", True, "shipped with motion2robot") for n in bundled_names()]
    for n in menagerie_config_names():
        ok, where = menagerie_available(n)
        entries.append(RobotEntry(MENAGERIE_PREFIX + n, "menagerie", ok, where))
    if not load:
        return entries
    out = []
    for e in entries:
        if not e.available:
            out.append(e)
            continue
        try:
            r = load_robot(e.name)
        except RobotConfigError as err:
            out.append(RobotEntry(e.name, e.origin, False, e.where, error=str(err)))
            continue
        out.append(RobotEntry(e.name, e.origin, True, e.where, r.n_joints, r.mass, r.height))
    return out


def joint_rows(robot: Robot) -> list[JointRow]:
    """The robot's hinges in model order with their limits, gains, nominal angle and servo ID."""
    servos = robot.config.servos.by_joint() if robot.config.servos else {}
    rows = []
    for i, n in enumerate(robot.joint_names):
        s = servos.get(n)
        rows.append(JointRow(
            name=n, lower=float(robot.lower[i]), upper=float(robot.upper[i]),
            velocity=float(robot.velocity_limit[i]), torque=float(robot.torque_limit[i]), kp=float(robot.kp[i]),
            nominal=float(robot.nominal_qpos[7 + i]), servo_id=s.id if s else None,
            reason=robot.config.joint(n).reason,
        ))
    return rows


def keypoint_rows(robot: Robot) -> list[tuple[str, str, tuple[float, float, float], float]]:
    """(SMPL keypoint, robot body, offset in that body's frame (m), weight) for each tracked keypoint.

    Site-based keypoints are reported as the site's body and position."""
    m = robot.model
    rows = []
    for human, sid, w in zip(robot.keypoints, robot.keypoint_sites, robot.keypoint_weights):
        body = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.site_bodyid[sid]))
        rows.append((human, body, tuple(float(v) for v in m.site_pos[sid]), float(w)))
    return rows


def model_top(robot: Robot) -> float:
    """Highest point of the robot's geometry (m) at the nominal pose, soles at z = 0 (axis-aligned
    bounding boxes of the geoms, so it may overstate by a few millimetres)."""
    m = robot.model
    d = robot.new_data()
    top = -np.inf
    for g in range(m.ngeom):
        c, h = m.geom_aabb[g, :3], m.geom_aabb[g, 3:]
        rot = d.geom_xmat[g].reshape(3, 3)
        z = d.geom_xpos[g, 2] + rot[2] @ c + np.abs(rot[2]) @ h
        top = max(top, float(z))
    return top


@dataclass(frozen=True)
class KeypointGap:
    """One SMPL keypoint in two configs of the same model: the body each uses and the distance (m)
    between the two points with both robots at ``b``'s nominal pose."""

    human: str
    body_a: str | None
    body_b: str | None
    gap: float | None


def compare_robots(a: Robot, b: Robot) -> tuple[list[KeypointGap], list[float]]:
    """Compare two configs of the same MJCF (e.g. a draft with a hand-written config): keypoints
    (union, in ``b``'s order then ``a``'s extras) and, per foot [left, right], the largest distance
    (m) between corresponding sole corners in the foot frame (NaN when the foot bodies differ)."""
    if a.model.nq != b.model.nq or a.joint_names != b.joint_names:
        raise RobotConfigError(f"{a.name} and {b.name} are not the same model (different joints); compare configs of one MJCF")
    da = mujoco.MjData(a.model)
    da.qpos[:] = b.nominal_qpos
    mujoco.mj_kinematics(a.model, da)
    db = b.new_data()
    body = {r.name: {k.human: (k.body if k.body else f"site {k.site}") for k in r.config.keypoints} for r in (a, b)}
    gaps = []
    for human in list(b.keypoints) + [k for k in a.keypoints if k not in b.keypoints]:
        ia = a.keypoints.index(human) if human in a.keypoints else None
        ib = b.keypoints.index(human) if human in b.keypoints else None
        gap = None
        if ia is not None and ib is not None:
            gap = float(np.linalg.norm(da.site_xpos[a.keypoint_sites[ia]] - db.site_xpos[b.keypoint_sites[ib]]))
        gaps.append(KeypointGap(human, body[a.name].get(human), body[b.name].get(human), gap))
    soles = []
    for fa, fb in zip(a.config.feet, b.config.feet):
        same = fa.body == fb.body
        soles.append(float(np.abs(np.array(fa.corners()) - np.array(fb.corners())).max()) if same else float("nan"))
    return gaps, soles

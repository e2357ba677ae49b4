"""Put a robot into one of the ``sim/`` worlds (floor, lights, cameras) for physics and rendering."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import mujoco

from motion2robot.errors import RobotConfigError
from motion2robot.robot.robot import Robot

WORLD_PREFIX = "world_"
FLOOR_GEOM = WORLD_PREFIX + "floor"


def worlds_dir() -> Path:
    """The folder of worlds shipped with the package (``sim/`` in the source tree)."""
    return Path(str(resources.files("motion2robot.worlds")))


def world_names() -> list[str]:
    return sorted(p.stem for p in worlds_dir().glob("*.xml"))


def make_world_spec(robot: Robot, world: str = "flat") -> mujoco.MjSpec:
    """An editable spec: the robot with the world's static geometry attached (names prefixed
    ``world_``; the floor is :data:`FLOOR_GEOM`).

    The robot keeps its names, options, actuators and the loader's added sites and ranges; its
    free root is the first joint, so ``qpos`` has the same layout as ``robot.model``'s."""
    path = worlds_dir() / f"{world}.xml"
    if not path.is_file():
        raise RobotConfigError(f"unknown world {world!r}; use one of {', '.join(world_names())}")
    world_spec = mujoco.MjSpec.from_file(str(path))
    spec = mujoco.MjSpec.from_file(robot.mjcf_path)
    _copy_robot_edits(robot, spec)
    spec.attach(world_spec, frame=spec.worldbody.add_frame(), prefix=WORLD_PREFIX)
    spec.visual.global_.offwidth = max(spec.visual.global_.offwidth, 1280)
    spec.visual.global_.offheight = max(spec.visual.global_.offheight, 960)
    return spec


def make_world(robot: Robot, world: str = "flat") -> mujoco.MjModel:
    """Compiled world + robot model (floor geom named ``floor``)."""
    model = make_world_spec(robot, world).compile()
    if model.nq != robot.model.nq:
        raise RobotConfigError(f"world {world!r}: has joints of its own; worlds must hold only static geometry")
    return model


def _copy_robot_edits(robot: Robot, spec: mujoco.MjSpec) -> None:
    """Apply the joint ranges and sites the loader added to ``robot.model`` onto a fresh spec."""
    m = robot.model
    ranges = dict(zip(robot.joint_names, zip(robot.lower, robot.upper)))
    for j in spec.joints:
        if j.name in ranges:
            j.range = list(ranges[j.name])
            j.limited = mujoco.mjtLimited.mjLIMITED_TRUE
    bodies = {b.name: b for b in spec.bodies if b.name}
    existing = {s.name for s in spec.sites}
    for sid in range(m.nsite):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_SITE, sid)
        if name in existing:
            continue
        body = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.site_bodyid[sid]))
        bodies[body].add_site(name=name, pos=list(m.site_pos[sid]), size=[0.003, 0, 0], group=5)

"""The MuJoCo models the checks run on, built from a :class:`Robot` and a ``sim/`` world.

- :func:`check_model`: the robot on the flat floor with every collision geom made mutually
  colliding (``contype = conaffinity = 1``), so that one ``mj_collision`` per frame reports both
  robot-robot and robot-floor contacts whatever the MJCF's own collision bitmasks say.
- :func:`physics_model`: the robot on the floor with the MJCF's actuators replaced by one
  servo-like position actuator per hinge (gain ``robot.kp``, force range ``+-robot.torque_limit``,
  damping topped up to ``MIN_DAMPING_TIME``); joint damping, armature and friction loss stay as
  the MJCF declares them.

Both keep the robot's qpos layout (free root xyz + wxyz quaternion, then the hinges).
"""

from __future__ import annotations

import functools
import warnings

import mujoco
import numpy as np

from motion2robot.robot.robot import Robot
from motion2robot.robot.world import FLOOR_GEOM, make_world_spec

#: s; the position servo's total damping is at least kp times this (a derivative gain is added
#: where the model's joint damping is lower).
MIN_DAMPING_TIME = 0.03


def _world_spec(robot: Robot) -> mujoco.MjSpec:
    with warnings.catch_warnings():  # the attach "integrator" notice of make_world_spec
        warnings.simplefilter("ignore", UserWarning)
        return make_world_spec(robot)


def _compile(spec: mujoco.MjSpec) -> mujoco.MjModel:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return spec.compile()


@functools.lru_cache(maxsize=8)
def check_model(robot: Robot) -> mujoco.MjModel:
    """Robot + floor, all collision geoms colliding with each other (cached per robot)."""
    spec = _world_spec(robot)
    for g in spec.geoms:
        if g.contype or g.conaffinity:
            g.contype, g.conaffinity = 1, 1
    return _compile(spec)


@functools.lru_cache(maxsize=8)
def mujoco_world_model(robot: Robot) -> mujoco.MjModel:
    """Robot + floor with the MJCF's own collision bitmasks (geom ids as in :func:`check_model`):
    what MuJoCo itself would test (cached per robot)."""
    return _compile(_world_spec(robot))


@functools.lru_cache(maxsize=8)
def physics_model(robot: Robot, timestep: float = 0.002) -> mujoco.MjModel:
    """Robot + floor with servo-like position actuators on every hinge, in ``joint_names`` order.

    Actuator i: ``ctrl`` = goal angle (rad), force = clip(kp * (ctrl - q) - kv * qdot,
    +-torque_limit); ``ctrlrange`` = the joint's range. kv tops the joint's own damping up to
    ``kp * MIN_DAMPING_TIME`` (0 for servos whose model damping already exceeds it, like the
    OP3's; models without joint damping, like the Menagerie G1, would otherwise oscillate as an
    undamped spring). ``timestep`` in seconds (cached per robot and step)."""
    spec = _world_spec(robot)
    for act in list(spec.actuators):
        spec.delete(act)
    damping = robot.model.dof_damping[robot.model.jnt_dofadr[np.asarray(robot.joint_ids)]]
    for i, name in enumerate(robot.joint_names):
        a = spec.add_actuator(name=f"servo_{name}", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        kv = max(0.0, float(robot.kp[i]) * MIN_DAMPING_TIME - float(damping[i]))
        a.set_to_position(kp=float(robot.kp[i]), kv=kv)
        a.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        a.forcerange = [-float(robot.torque_limit[i]), float(robot.torque_limit[i])]
        a.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        a.ctrlrange = [float(robot.lower[i]), float(robot.upper[i])]
    spec.option.timestep = float(timestep)
    return _compile(spec)


def floor_geom(model: mujoco.MjModel) -> int:
    return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, FLOOR_GEOM)


def body_name(model: mujoco.MjModel, body: int) -> str:
    return mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(body)) or f"body{int(body)}"


def collidable_bodies(model: mujoco.MjModel) -> np.ndarray:
    """(nbody,) bool: bodies owning at least one geom that takes part in collisions."""
    out = np.zeros(model.nbody, dtype=bool)
    active = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
    out[np.unique(model.geom_bodyid[active])] = True
    return out

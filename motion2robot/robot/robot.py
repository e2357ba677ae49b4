"""The :class:`Robot`: a compiled MuJoCo model plus its validated configuration, as arrays.

The model is the robot alone (no floor): a free root joint followed by hinges. The loader adds
sites ``kp_<keypoint>`` for body-based keypoints and ``sole_<side>_<0..3>`` (corners) /
``sole_<side>_c`` (centre) on the feet, and applies the config's joint ranges (all limited).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import mujoco
import numpy as np

from motion2robot.robot.config import RobotConfig


@dataclass(frozen=True, eq=False)
class Robot:
    """A humanoid ready for retargeting, checking and streaming.

    name: as resolved (``op3``, ``menagerie:unitree_g1``, or the config path).
    source: where it came from, for people (``bundled``, ``menagerie (...)``, a path).
    model: the compiled kinematic model (robot only, no floor), qpos = [root xyz, root wxyz, hinges].
    joint_names: hinge names in model order; ``lower``/``upper`` (rad), ``velocity_limit``
        (rad/s), ``torque_limit`` (N*m), ``kp`` (N*m/rad) per hinge in that order.
    nominal_qpos: (7 + n,) nominal standing posture with the lowest sole corner at z = 0.
    keypoints: SMPL22 names tracked, in config order; ``keypoint_sites`` their site ids,
        ``keypoint_weights`` their tracking weights.
    sole_sites: (2, 4) site ids of the sole corners [left, right]; ``sole_center_sites`` (2,).
    foot_bodies: (2,) body ids [left, right]; ``root_body``, ``torso_body`` body ids.
    mass: total mass (kg); height: highest keypoint at the nominal pose (m); model_hash: hex digest.
    """

    name: str
    source: str
    config: RobotConfig
    model: mujoco.MjModel
    mjcf_path: str
    joint_names: tuple[str, ...]
    joint_ids: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    velocity_limit: np.ndarray
    torque_limit: np.ndarray
    kp: np.ndarray
    nominal_qpos: np.ndarray
    keypoints: tuple[str, ...]
    keypoint_sites: np.ndarray
    keypoint_weights: np.ndarray
    sole_sites: np.ndarray
    sole_center_sites: np.ndarray
    foot_bodies: np.ndarray
    root_body: int
    torso_body: int
    mass: float
    height: float
    model_hash: str

    @property
    def nq(self) -> int:
        return int(self.model.nq)

    @property
    def n_joints(self) -> int:
        return len(self.joint_names)

    def new_data(self) -> mujoco.MjData:
        """A fresh MjData at the nominal pose (kinematics computed)."""
        data = mujoco.MjData(self.model)
        data.qpos[:] = self.nominal_qpos
        mujoco.mj_kinematics(self.model, data)
        return data

    @functools.cached_property
    def nominal_site_xpos(self) -> np.ndarray:
        """(nsite, 3) world positions (m) of every site at the nominal pose (read-only)."""
        out = self.new_data().site_xpos.copy()
        out.flags.writeable = False
        return out

    def joint_index(self, name: str) -> int:
        """Index of hinge ``name`` in ``joint_names``."""
        try:
            return self.joint_names.index(name)
        except ValueError:
            raise KeyError(f"{self.name} has no joint {name!r}") from None

"""Where each drafted keypoint should be: the joint centre it stands for, defined from the MJCF's
joint positions (independently of the drafting code), for the Menagerie humanoids.

A centre is the point nearest (least squares) to the axis lines of the joints listed for it (one
joint: its anchor); the pelvis is the midpoint of the two hip centres. Keypoints without a joint
(foot, spine, neck, head; wrists of arms without wrist joints) have no centre here.
"""

from __future__ import annotations

import re

import mujoco
import numpy as np

#: robot -> keypoint kind -> regex of its joints' names ({s}: the side as the model spells it).
JOINTS = {
    "robotis_op3": {"sides": ("l", "r"), "hip": r"{s}_hip_(yaw|roll|pitch)", "knee": r"{s}_knee",
                    "ankle": r"{s}_ank_(pitch|roll)", "shoulder": r"{s}_sho_(pitch|roll)", "elbow": r"{s}_el"},
    "unitree_g1": {"sides": ("left", "right"), "hip": r"{s}_hip_\w+_joint", "knee": r"{s}_knee_joint",
                   "ankle": r"{s}_ankle_\w+_joint", "shoulder": r"{s}_shoulder_\w+_joint", "elbow": r"{s}_elbow_joint",
                   "wrist": r"{s}_wrist_\w+_joint"},
    "unitree_h1": {"sides": ("left", "right"), "hip": r"{s}_hip_\w+", "knee": r"{s}_knee", "ankle": r"{s}_ankle",
                   "shoulder": r"{s}_shoulder_\w+", "elbow": r"{s}_elbow"},
    "pal_talos": {"sides": ("left", "right"), "hip": r"leg_{s}_[123]_joint", "knee": r"leg_{s}_4_joint",
                  "ankle": r"leg_{s}_[56]_joint", "shoulder": r"arm_{s}_[23]_joint", "elbow": r"arm_{s}_4_joint",
                  "wrist": r"arm_{s}_[567]_joint"},
    "fourier_n1": {"sides": ("left", "right"), "hip": r"{s}_hip_\w+_joint", "knee": r"{s}_knee_pitch_joint",
                   "ankle": r"{s}_ankle_\w+_joint", "shoulder": r"{s}_shoulder_\w+_joint",
                   "elbow": r"{s}_elbow_pitch_joint", "wrist": r"{s}_wrist_yaw_joint"},
}


def _meet(points: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    a, b = 1e-9 * np.eye(3), 1e-9 * points.mean(axis=0)
    for p, d in zip(points, dirs):
        proj = np.eye(3) - np.outer(d, d) / (d @ d)
        a, b = a + proj, b + proj @ p
    return np.linalg.solve(a, b)


def joint_centres(name: str, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, np.ndarray]:
    """SMPL keypoint name -> its joint centre (world, m) at the pose in ``data`` (after kinematics)."""
    spec = JOINTS[name]
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or "" for j in range(model.njnt)]
    out = {}
    for side, s in zip(("left", "right"), spec["sides"]):
        for kind, pattern in spec.items():
            if kind == "sides":
                continue
            ids = [j for j, n in enumerate(names) if re.fullmatch(pattern.format(s=s), n)]
            assert ids, (name, kind, side)
            out[f"{side}_{kind}"] = _meet(data.xanchor[ids], data.xaxis[ids])
    out["pelvis"] = (out["left_hip"] + out["right_hip"]) / 2
    return out


def keypoint_errors(name: str, robot) -> dict[str, float]:
    """Drafted keypoint -> its distance (m) from the joint centre, at the robot's nominal pose."""
    d = robot.new_data()
    centres = joint_centres(name, robot.model, d)
    return {k: float(np.linalg.norm(d.site_xpos[s] - centres[k]))
            for k, s in zip(robot.keypoints, robot.keypoint_sites) if k in centres}

"""Which hinges move which foot: the kinematic chains from the root to the soles, shared by the
checks (contact Jacobians) and the retargeter (limbs no foot constraint holds)."""

from __future__ import annotations

import numpy as np

from motion2robot.robot.robot import Robot


def foot_ancestor_mask(robot: Robot) -> np.ndarray:
    """(n, 2) bool: hinge j moves foot k (lies on the path from the root to that foot)."""
    m = robot.model
    jbody = m.jnt_bodyid[np.asarray(robot.joint_ids)]
    out = np.zeros((robot.n_joints, 2), dtype=bool)
    for k, foot in enumerate(np.asarray(robot.foot_bodies)):
        chain = set()
        b = int(foot)
        while b > 0:
            chain.add(b)
            b = int(m.body_parentid[b])
        out[:, k] = [int(b) in chain for b in jbody]
    return out


def free_limbs(robot: Robot) -> np.ndarray:
    """(n,) bool hinges on no path from the root to a foot (arms, head, waist above the legs)."""
    return ~foot_ancestor_mask(robot).any(axis=1)


def hip_hinges(robot: Robot) -> list[int]:
    """[left, right] index (in ``robot.joint_names``) of each leg's first hinge from the root: the
    hip, whose anchor is where the leg hangs from."""
    mask = foot_ancestor_mask(robot)
    return [int(np.flatnonzero(mask[:, f])[0]) for f in range(mask.shape[1])]

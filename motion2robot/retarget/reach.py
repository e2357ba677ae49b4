"""Exact reach: a human motion the robot can perform exactly is retargeted to exactly that.

A human motion is *robot-shaped* for a robot when, scaled to it, every keypoint of every frame
is where the robot's keypoints are in one pose of the robot within its joint limits, and that
pose is the only one nearby (the keypoints fix every degree of freedom, root included). Such a
motion is what :func:`~motion2robot.projection.project` makes (the robot's own motion mapped
back into the human's space), or a robot's recording drawn as a skeleton. Its best retargeting
is that pose, frame by frame: the whole-body solve would pull it a few mm off (its posture,
temporal and orientation terms weigh against targets it could reach), and the retargeting of
the robot's own motion would then not be that motion. Everything else is rejected in
microseconds, before any solve (:func:`robot_scale`).

1. **scale** (:func:`robot_scale`): the robot's keypoint pairs that are a rigid distance apart
   in every pose (:func:`rigid_bones`: both ends on one body, or across joints whose axes pass
   through the end, found by sampling poses) and whose SMPL22 path is scaled by one ratio of
   :class:`~.scale.Scale`. Each such bone of the human gives that ratio in every frame; they all
   agree within RATIO_TOLERANCE for a robot-shaped motion (a human's bones are in the human's
   proportions, never the robot's: the clip is rejected here). The clip's own
   :func:`~.scale.auto_scale` is not used: it measures the leg chain hip -> knee -> ankle, whose
   length on a robot with offset hip axes changes with the pose (0.5 % on op3), so a motion
   made at one scale would be measured at another;
2. **pose** (:func:`reach_poses`): Gauss-Newton on the keypoint residual alone, the root placed
   by the best rigid fit of the nominal pose to frame 0's targets, each frame from the one
   before. A frame is reached when its largest keypoint residual is below TOLERANCE_M, every
   hinge is within its limits, and the joints the residual can hide (its norm over the keypoint
   Jacobian's smallest singular value) stay below JOINT_TOLERANCE: no joint the keypoints leave
   free, so the pose is the motion's, not one of many (a straight arm or leg leaves the
   Jacobian ill-conditioned, not singular: reached to rounding, its pose is still fixed).

Units: metres (robot scale), radians; world frame z up.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import mujoco
import numpy as np

from motion2robot.motion.human import KP, SMPL22, SMPL22_PARENTS
from motion2robot.retarget.scale import BONE_GROUP, Scale
from motion2robot.robot.robot import Robot

#: m: a frame is reached when no keypoint is further than this from its target (robot scale).
TOLERANCE_M = 1e-6
#: Relative spread allowed between the scale ratios the rigid bones give, over bones and frames.
RATIO_TOLERANCE = 1e-6
#: rad: the largest joint error a reached frame's residual may leave (its norm over the keypoint
#: Jacobian's smallest singular value, m / (m/rad); a joint that moves no keypoint: infinite).
#: A tenth of the projection's idempotence tolerance, above what float32 targets leave (a
#: sampler's tensors: about 1e-5 rad where the Jacobian is well conditioned).
JOINT_TOLERANCE = 1e-4
#: rad: a hinge this little past a limit is on it (the targets' rounding) and is put back on it.
LIMIT_SLACK = 1e-6
#: Gauss-Newton iterations per frame at most (a reachable frame converges in 2-5 from the last).
ITERATIONS = 60
#: rad (or m for the root): the largest change of any coordinate in one iteration (far from the
#: answer, as frame 0 starts, a full Gauss-Newton step can wind a joint round many turns).
MAX_STEP = 0.25
#: Poses sampled within the joint limits to tell a rigid keypoint pair (distance spread below RIGID_M).
SAMPLES = 24
RIGID_M = 1e-9


@dataclass(frozen=True)
class RigidBone:
    """Keypoints ``parent`` -> ``child`` (SMPL22 indices) a fixed ``length`` (m) apart on the robot
    in every pose; their human distance is scaled by the ratio ``group``."""

    parent: int
    child: int
    group: str
    length: float


def _kinematics(robot: Robot, data: mujoco.MjData, q: np.ndarray) -> np.ndarray:
    data.qpos[:] = q
    mujoco.mj_kinematics(robot.model, data)
    return data.site_xpos[robot.keypoint_sites].copy()


@functools.lru_cache(maxsize=16)
def rigid_bones(robot: Robot) -> tuple[RigidBone, ...]:
    """The robot's rigid keypoint pairs along the SMPL22 tree (each child with its nearest tracked
    ancestor, the path between them in one scale group)."""
    mapped = {KP[k]: i for i, k in enumerate(robot.keypoints)}
    rng = np.random.default_rng(0)
    data = mujoco.MjData(robot.model)
    poses = [robot.nominal_qpos.copy() for _ in range(SAMPLES)]
    for q in poses[1:]:
        q[7:] = rng.uniform(robot.lower, robot.upper)
    pts = np.stack([_kinematics(robot, data, q) for q in poses])  # (S, k, 3)
    bones = []
    for child, ci in mapped.items():
        groups, j = set(), child
        while j != 0 and (j == child or j not in mapped):
            groups.add(BONE_GROUP[SMPL22[j]])
            j = SMPL22_PARENTS[j]
        if j not in mapped or len(groups) != 1:
            continue
        d = np.linalg.norm(pts[:, ci] - pts[:, mapped[j]], axis=-1)
        if d.max() - d.min() < RIGID_M and d[0] > 1e-6:
            bones.append(RigidBone(j, child, groups.pop(), float(d[0])))
    return tuple(bones)


def robot_scale(positions: np.ndarray, robot: Robot) -> Scale | None:
    """The scale at which ``positions`` ((T, 22, 3) human keypoints, m) has the robot's rigid bone
    lengths exactly, or None when no single ratio per group does (any human's own proportions)
    or a group has no rigid bone to measure it."""
    ratios: dict[str, list[np.ndarray]] = {"legs": [], "arms": [], "height": []}
    for b in rigid_bones(robot):
        human = np.linalg.norm(positions[:, b.child] - positions[:, b.parent], axis=-1)
        if np.any(human < 1e-9):
            return None
        ratios[b.group].append(b.length / human)
    values = {}
    for group, rs in ratios.items():
        if not rs:
            return None
        r = np.concatenate(rs)
        mid = float(np.median(r))
        if not np.all(np.abs(r / mid - 1.0) <= RATIO_TOLERANCE):
            return None
        values[group] = mid
    return Scale(values["legs"], values["arms"], values["height"], (("legs", "reach"), ("arms", "reach"),
                                                                  ("height", "reach")))


def _fit_root(robot: Robot, data: mujoco.MjData, targets: np.ndarray) -> np.ndarray:
    """The nominal pose moved rigidly (root rotation and translation) onto ``targets`` (k, 3) by
    the least-squares rigid fit of its keypoints."""
    q = robot.nominal_qpos.copy()
    p = _kinematics(robot, data, q)
    pc, tc = p.mean(axis=0), targets.mean(axis=0)
    u, _, vt = np.linalg.svd((targets - tc).T @ (p - pc))
    R = u @ np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))]) @ vt
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, R.ravel())
    rot = np.empty(4)
    mujoco.mju_mulQuat(rot, quat, q[3:7])
    q[3:7] = rot / np.linalg.norm(rot)
    q[:3] = R @ (q[:3] - pc) + tc
    return q


def _jacobian(robot: Robot, data: mujoco.MjData, jac: np.ndarray) -> np.ndarray:
    for i, s in enumerate(robot.keypoint_sites):
        mujoco.mj_jacSite(robot.model, data, jac[3 * i:3 * i + 3], None, int(s))
    return jac


def _held(robot: Robot, q: np.ndarray, dv: np.ndarray) -> np.ndarray:
    """(nv,) bool: the hinges on a limit (put there by the iteration's clip) that the step ``dv``
    pushes past it (projected Gauss-Newton: with the step clipped instead, such a hinge stalled the
    other joints short of a pose on the limit, a shoulder roll at its end)."""
    hinges, step = q[7:], dv[6:]
    out = np.zeros(len(dv), dtype=bool)
    out[6:] = ((hinges <= robot.lower) & (step < 0)) | ((hinges >= robot.upper) & (step > 0))
    return out


def _reach_frame(robot: Robot, data: mujoco.MjData, q: np.ndarray, target: np.ndarray) -> bool:
    """Gauss-Newton in place on ``q`` towards ``target`` (k, 3); True when reached (see the module text)."""
    jac = np.zeros((3 * len(robot.keypoint_sites), robot.model.nv))
    for _ in range(ITERATIONS):
        r = (target - _kinematics(robot, data, q)).ravel()
        if np.abs(r).max() < 1e-13:  # float64 rounding of the kinematics at a robot's size
            break
        mujoco.mj_comPos(robot.model, data)
        J = _jacobian(robot, data, jac)
        dv = np.linalg.lstsq(J, r, rcond=None)[0]
        held = _held(robot, q, dv)
        if held.any():  # a hinge on a limit the step would push past stays there: the step without it
            dv = np.zeros_like(dv)
            dv[~held] = np.linalg.lstsq(J[:, ~held], r, rcond=None)[0]
        size = float(np.abs(dv).max())
        if size < 1e-12:  # converged to the least-squares pose (a target rounded to float32, say)
            break
        dv *= min(1.0, MAX_STEP / size)
        mujoco.mj_integratePos(robot.model, q, dv, 1.0)
        q[7:] = np.clip(q[7:], robot.lower, robot.upper)  # on a limit, held there (:func:`_held`)
    hinges = q[7:]
    if np.any(hinges < robot.lower - LIMIT_SLACK) or np.any(hinges > robot.upper + LIMIT_SLACK):
        return False
    q[7:] = np.clip(hinges, robot.lower, robot.upper)  # a pose on a limit, reached to rounding
    r = target - _kinematics(robot, data, q)
    if not np.linalg.norm(r, axis=-1).max() < TOLERANCE_M:
        return False
    mujoco.mj_comPos(robot.model, data)
    smallest = np.linalg.svd(_jacobian(robot, data, jac), compute_uv=False)[-1]
    return bool(np.linalg.norm(r) <= JOINT_TOLERANCE * smallest)


def reach_poses(targets: np.ndarray, robot: Robot) -> np.ndarray | None:
    """(T, nq) poses reaching ``targets`` ((T, k, 3) robot keypoints in ``robot.keypoints``
    order, m, world) exactly, or None at the first frame that is not reached."""
    data = mujoco.MjData(robot.model)
    out = np.empty((len(targets), robot.nq))
    q = _fit_root(robot, data, targets[0])
    for t, target in enumerate(targets):
        if not _reach_frame(robot, data, q, target):
            return None
        out[t] = q
    return out


def robot_shaped(positions: np.ndarray, robot: Robot, scale: Scale | None = None) -> tuple[Scale, np.ndarray] | None:
    """(scale, (T, nq) poses) when ``positions`` ((T, 22, 3) canonical human keypoints, m, z up)
    is robot-shaped (the module text), else None. ``scale``: a forced scale (default: measured
    by :func:`robot_scale`)."""
    from motion2robot.retarget.scale import scaled_keypoints

    scale = scale or robot_scale(positions, robot)
    if scale is None:
        return None
    kp = scaled_keypoints(np.asarray(positions, dtype=np.float64), scale)
    poses = reach_poses(kp[:, [KP[k] for k in robot.keypoints]], robot)
    return None if poses is None else (scale, poses)

"""Projection onto what the robot can do: ``project(human) -> human'``.

``project`` retargets a human motion with the default executable retargeting (tempo and legs
chosen by ``check``, :mod:`~motion2robot.retarget.executable`) and maps the robot's motion back
into the human's space, so a sampler can replace an intermediate sample by what the robot can
actually perform, and a user can see the robot's version beside the original.

The way back (:func:`project_motion`, pure apart from MuJoCo's forward kinematics):

1. **time**: human frame i (at the human's rate f_h) is robot frame ``u_i = i * k * f_r / f_h``
   (k: the tempo factor the retargeter chose, ``meta["tempo"]``; f_r: the robot motion's rate);
   the robot's poses are interpolated there in joint space (natural cubic spline, as the tempo
   stretch itself does: :func:`~motion2robot.retarget.retime.sample_poses`), so every frame of
   ``human'`` is a pose the robot takes (robot-shaped, :mod:`~motion2robot.retarget.reach`, at
   any tempo), its keypoints taken from them and its contact labels at the nearest frame;
2. **scale**: the robot's keypoints are the targets the retargeter would have had for a human
   whose pelvis path is scaled by ``legs`` and each bone by its group's ratio
   (:func:`~motion2robot.retarget.scale.scaled_keypoints`, ratios from ``meta["scale"]``). That
   map is inverted from the pelvis outwards, so scaling ``human'`` again gives back exactly the
   robot's keypoints;
3. **joints the robot has no keypoint for** (on the shipped robots the spine and collar joints,
   all on the torso) are filled from the original pose rigidly in the torso frame: each keeps
   its offset from the neck in the original's torso frame (up = spine1 -> neck, left = right hip
   -> left hip), placed in the robot's torso frame (up = the robot torso's up axis, left = its
   hip keypoints). So ``spine1' -> neck'`` points along the robot's torso exactly (the direction
   the retargeter's ``torso_up`` term reads) and the collars ride with the robot's shoulders'
   torso. A filled joint off the torso (a drafted robot without, say, wrists) keeps its offset
   from its parent, turned with the torso the same way;
4. **contacts**: ``human'.contacts`` are the contact labels the robot motion was made with, so
   ``human'`` says where the robot's soles were planted (a ``steps`` result's: the schedule its
   walking pattern walked, ``meta["schedule"]``, in which a foot the clip starts or ends in the
   air is in the air, as in the human's, though the robot stands it at its nearest placement);
5. **exactly reached**: every frame of the direct mapping is a pose of the robot's, so the default
   retargeting (tempo and legs ``auto``) reaches it exactly (:mod:`~motion2robot.retarget.reach`)
   and, for a slowed result, plays those poses at the tempo chosen
   (:mod:`~motion2robot.retarget.replay`): when that is the robot motion to ``tolerance``,
   ``human'`` is the direct mapping (:attr:`Projection.reached`; every dev clip, 66 of 66) and
   nothing below runs. Otherwise (a fixed tempo or legs, another rate, ``reach`` off):
6. **target correction** (:func:`refine`): the retargeter's optimum for targets it can reach
   exactly is not exactly the pose that reaches them (its regularisation, temporal and
   orientation terms pull it away, a few mm at the robot's scale), and the scale it computes from
   ``human'``'s own bone lengths differs slightly from the original's (a robot's leg keypoints
   are not a rigid chain). So ``human'`` is corrected by fixed-point rounds
   ``h <- h + (P(q0) - P(R(h)))`` (P: steps 1-4, R: the retargeting at the chosen tempo and legs,
   q0 the robot motion of the original) until its robot motion is within :data:`TOLERANCE` rad
   RMS of q0: ``human'`` is then a human motion whose retargeting *is* the robot motion, found
   from the robot's own keypoints. The retargeting passes on only part of a change of its targets
   (its few block-Jacobi iterations, damped by the temporal terms: a fifth to two thirds on
   weakly held joints such as the head tilt and the elbows), so each round is aimed past q0 by
   the inverse of that share (:mod:`~.attenuation`: P(aim) instead of P(q0)), damped further
   when a round overshoots or the rounds stall. The rounds run in two phases: first against the
   retargeting cut after its solves (:func:`solver_stages`: R without the servo rounds, joint
   smoothing, ZMP stage and root pass), then against the whole retargeting from where the first
   phase ended. The later stages pass on a motion they made almost as it is (0.0002 rad on an
   MDM throw), but they are filters with thresholds (a row over its acceleration target is
   smoothed in every joint), which a solve's small error crosses and no round can aim through;
   with the solves on q0 first they mostly stay off. (Of these a ``steps`` result's walking
   pattern runs the smoothing alone, of the upper body it takes from the free solve: its first
   phase corrects against the pattern with that body's velocity clamp only; 9 of the 32 clips on
   ``steps`` ended closer, 6 further, the median 0.0022 -> 0.0018 rad.) The rounds keep
   ``human'`` a skeleton: each round's bones keep the directions it gives them and lengths within
   :data:`BONE_SLACK` of the direct mapping's, frame by frame (:func:`keep_bones`; free, the
   rounds stretched arms by up to 43 % to pull a robot's elbows straighter, and the legs of a
   HumanML3D clip sitting on the floor to 3.8 m; MDM's own samples vary their bones by 9-17 %
   at the 95th percentile). :attr:`Projection.bone_drift` says how far the returned one went.
   :attr:`Projection.direct`
   keeps steps 1-4 alone (what the viewer and the report draw).

``human'`` is in the original's canonical frame (metres, z up, same floor and heading);
:attr:`Projection.positions` gives it in the input's own axes and units (for arrays and tensors:
the layout the sampler holds, e.g. HumanML3D's y-up joints). The per-joint distance between the
original and ``human'`` (metres, per frame) comes with it.
"""

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from motion2robot.motion.human import SMPL22, HumanMotion
from motion2robot.projection.attenuation import Attenuation, attenuation
from motion2robot.projection.correction import (
    BONE_SLACK,
    MEMORY,
    ROUNDS,
    SOLVER_TOLERANCE,
    TOLERANCE,
    chosen_solve,
    hinge_rms,
    refine,
    solver_stages,
)
from motion2robot.projection.inputs import MotionArrayError, as_human
from motion2robot.projection.mapping import project_motion, robot_points
from motion2robot.projection.maths import (
    bone_drift,
    bone_lengths,
    fill_torso,
    keep_bones,
    from_canonical,
    human_torso,
    joint_distance,
    robot_frames,
    torso_rotations,
    unscale,
)
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion

__all__ = [
    "BONE_SLACK",
    "MEMORY",
    "ROUNDS",
    "SOLVER_TOLERANCE",
    "TOLERANCE",
    "Attenuation",
    "MotionArrayError",
    "Projection",
    "as_human",
    "attenuation",
    "bone_drift",
    "bone_lengths",
    "chosen_solve",
    "fill_torso",
    "from_canonical",
    "hinge_rms",
    "human_torso",
    "joint_distance",
    "keep_bones",
    "project",
    "project_motion",
    "refine",
    "robot_frames",
    "robot_points",
    "solver_stages",
    "torso_rotations",
    "unscale",
]


@dataclass(frozen=True, eq=False)
class Projection:
    """The result of :func:`project`.

    human: ``human'``, the robot's version in the human's space (canonical frame, metres, the
        original's frame count and fps; ``contacts`` the robot's planted soles).
    original: the canonical human motion that was projected.
    robot_motion: the robot motion ``human'`` was made from (the executable retargeting).
    report: the ``check`` report of the chosen attempt (None when neither tempo nor legs was
        ``auto``: nothing judged).
    distance: (T, 22) distance (m) between each joint of the original and of ``human'``.
    positions: (T, 22, 3) ``human'`` in the input's own axes and units (see the module text).
    direct: the robot's keypoints mapped back without the target correction (steps 1-4).
    rounds: the hinge RMS (rad) between the robot motion and the retargeting of each round's
        ``human'`` (the smallest is ``human``'s, the best round's; see :func:`refine`).
    solver_rounds: the same for the first phase of the correction, against the retargeting's
        solves alone (:func:`solver_stages`: the pipeline cut before its servo rounds).
    reached: ``human'`` is the direct mapping, which the retargeting reaches exactly
        (:mod:`~motion2robot.retarget.reach`): no correction ran (``rounds`` holds its one RMS).
    """

    human: HumanMotion
    original: HumanMotion
    robot_motion: RobotMotion
    report: Any
    distance: np.ndarray
    positions: np.ndarray
    direct: HumanMotion
    rounds: tuple[float, ...] = ()
    solver_rounds: tuple[float, ...] = ()
    reached: bool = False

    @property
    def idempotence_rms(self) -> float | None:
        """RMS (rad) over frames and hinges between the robot motion and the retargeting of
        ``human'`` at the same tempo and legs (the best round's: the ``human'`` returned; None
        when no round ran)."""
        return min(self.rounds) if self.rounds else None

    @property
    def bone_drift(self) -> float:
        """The largest relative change of a bone's length in any frame of ``human'`` from the direct
        mapping's (:func:`~.maths.bone_drift`; the correction keeps it within BONE_SLACK)."""
        return bone_drift(self.human.positions, self.direct.positions)

    @property
    def executable(self) -> bool | None:
        """The robot motion passed ``check`` (None when it was not judged)."""
        return None if self.report is None else bool(self.report.feasible)

    @property
    def joint_distance(self) -> dict[str, float]:
        """Mean over frames of the distance (m) per SMPL22 joint."""
        return {name: float(d) for name, d in zip(SMPL22, self.distance.mean(axis=0))}

    @property
    def mean_distance(self) -> float:
        """Mean over frames and joints of the distance (m)."""
        return float(self.distance.mean())

    def summary(self) -> str:
        """One line: executability, tempo, fallback, mean and largest per-joint distance."""
        meta = self.robot_motion.meta
        worst = max(self.joint_distance.items(), key=lambda kv: kv[1])
        fb = meta.get("fallback")
        exe = {None: "not judged", True: "executable", False: "NOT executable"}[self.executable]
        return (f"{self.robot_motion.robot}: {exe}, tempo x{float(meta.get('tempo', 1.0)):.2f}"
                + (f", legs {fb['mode']}" if isinstance(fb, Mapping) else "")
                + f"; human' is {100 * self.mean_distance:.1f} cm from the original on average "
                  f"(largest: {worst[0]} {100 * worst[1]:.1f} cm)")


def _aim(motion: RobotMotion, robot: Robot, options: Any):
    """The correction rounds' aim (:meth:`Attenuation.aim`), the attenuation computed at the first
    round that needs it (for a ``steps`` result, of the free-feet stage alone: the walking pattern
    takes the upper body from it; with the pinned stage's iterations in the model, 8 walks and
    throws on ``steps`` ended at a median 0.0025 rad instead of 0.0015, a HumanML3D walk at 0.0041
    instead of 0.0014)."""
    from dataclasses import replace

    from motion2robot.retarget.api import RetargetOptions
    from motion2robot.retarget.executable import legs_of

    made: list[Attenuation] = []

    def aim(current: RobotMotion, mu: float) -> RobotMotion:
        if not made:
            opt = options or RetargetOptions()
            tracked = legs_of(motion) != "steps"
            if not tracked:  # the walking pattern runs the free-feet stage alone
                opt = replace(opt, iterations=(opt.iterations[0], 0))
            made.append(attenuation(motion, robot, opt, tracked_legs=tracked))
        return made[0].aim(current, mu)

    return aim


def _reached(direct: HumanMotion, motion: RobotMotion, robot: Robot, options: Any) -> float | None:
    """Hinge RMS (rad) between ``motion`` and the exact poses of ``direct`` (the robot's own
    poses mapped back: robot-shaped when it keeps the robot's frames), played at ``motion``'s
    tempo (:mod:`~motion2robot.retarget.retime`: as the policy plays them), or None when the
    retargeting does not reach ``direct`` exactly (``reach`` off; another rate; a slowed motion
    retargeted at a fixed tempo or legs, which stretches the keypoints and solves them)."""
    from motion2robot.retarget.api import RetargetOptions
    from motion2robot.retarget.exact import exact_motion
    from motion2robot.retarget.retime import retime

    opt = options or RetargetOptions()
    tempo = float(motion.meta.get("tempo") or 1.0)
    if opt.fps is not None and abs(opt.fps - direct.fps) > 1e-9:
        return None
    if tempo != 1.0 and not (opt.tempo == "auto" and opt.legs == "auto"):
        return None  # a fixed tempo stretches the keypoints and solves: only the policy plays poses slower
    exact = exact_motion(direct, robot, opt)
    if exact is None:
        return None
    return hinge_rms(exact if tempo == 1.0 else retime(exact, robot, tempo, direct.num_frames), motion)


def project(motion: Any, robot: str | Robot = "op3", *, options: Any = None, check_options: Any = None,
            layout: str = "humanml3d_joints", fps: float | None = None, mean: Any = None, std: Any = None,
            rounds: int = ROUNDS, tolerance: float = TOLERANCE) -> Projection:
    """Project one human motion onto what ``robot`` can do (see the module text).

    motion: a :class:`HumanMotion`, or one sample as a numpy array or tensor in ``layout``
    ((T, 22, 3) HumanML3D joints, y up, metres, 20 fps unless ``fps``; (T, 263) features with
    optional ``mean``/``std``; ...). options: RetargetOptions (default: the executable
    retargeting, tempo and legs ``auto``); check_options: the judge's CheckOptions; rounds /
    tolerance: of the target correction (:func:`refine`, each phase at most ``rounds`` rounds;
    ``rounds=1`` only measures).
    Raises MotionArrayError (a ValueError and UserError) for bad arrays, UserError subclasses for
    motions or robots that cannot be retargeted."""
    from motion2robot.retarget.api import retarget_and_check
    from motion2robot.robot.loader import load_robot

    human = as_human(motion, layout=layout, fps=fps, mean=mean, std=std)
    rb = robot if isinstance(robot, Robot) else load_robot(robot)
    robot_motion, report = retarget_and_check(human, rb, options, check_options)
    direct = project_motion(robot_motion, rb, human)
    rms = _reached(direct, robot_motion, rb, options)
    reached = rms is not None and rms <= tolerance  # the retargeting reaches the robot's poses exactly
    if reached:
        projected, errors, solver_errors = direct, (rms,), ()
    else:
        aim = _aim(robot_motion, rb, options)
        solved, solver_errors = refine(direct, robot_motion, rb,
                                       chosen_solve(robot_motion, rb, solver_stages(options)),
                                       rounds, tolerance * SOLVER_TOLERANCE, aim=aim)
        projected, errors = refine(solved, robot_motion, rb, chosen_solve(robot_motion, rb, options), rounds,
                                   tolerance, aim=aim, reference=direct)
    positions = from_canonical(human.meta.get("canonical_transform"), projected.positions)
    return Projection(human=projected, original=human, robot_motion=robot_motion, report=report,
                      distance=joint_distance(human.positions, projected.positions), positions=positions,
                      direct=direct, rounds=errors, solver_rounds=solver_errors, reached=reached)

"""A slowed pass played again nearer the generated tempo, and a robot-shaped motion's exact poses
played slower: the two ways the tempo policy (:mod:`~.executable`) reuses poses it already has.

- :func:`replayed`: the slowed pass's own keypoints mapped back into the human's space at the
  human's tempo (``replay``, the way back of :mod:`motion2robot.projection`), retargeted in its
  legs mode at x1.0 and judged;
- :func:`retimed`: a motion's poses played at each factor of a list in turn
  (:func:`~.retime.retime`), the first that passes kept. For a slowed pass, the factors faster
  than its own: the poses the robot could hold at the slow pace, at a pace nearer the human's.
  For the exact poses of a robot-shaped motion (:mod:`~.exact`, what ``project`` returns) that
  fail at x1.0, the slower factors: so the robot's own motion of a slowed clip, mapped back to
  the human's tempo, is played at the tempo it was made at, its poses unchanged (the frames
  between the human's interpolated in joint space, 2e-5 rad RMS from the original on an AIST++
  dance slowed x1.6), which is what makes ``project`` exact for slowed clips too.
"""

from __future__ import annotations

from collections.abc import Callable

from motion2robot.motion.human import HumanMotion
from motion2robot.retarget.attempt import Attempt, tempo_proof
from motion2robot.retarget.footholds import PatternError
from motion2robot.retarget.retime import retime
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion


def replayed(slowed: Attempt, replay: Callable[[RobotMotion], HumanMotion],
             solve: Callable[[HumanMotion, str], RobotMotion], judge: Callable[[RobotMotion], object]) -> Attempt | None:
    """The ``slowed`` attempt replayed at x1.0 (see the module text); None when its legs give no
    pattern there."""
    try:
        motion = solve(replay(slowed.motion), slowed.legs)
    except PatternError:
        return None
    return Attempt(slowed.legs, 1.0, motion, judge(motion), replay_of=slowed.factor)


def retimed(base: Attempt, factors: list[float], robot: Robot, human_frames: int,
            judge: Callable[[RobotMotion], object]) -> tuple[Attempt | None, list[Attempt]]:
    """``base``'s motion played at each of ``factors`` in order (see the module text): the first
    passing attempt (None if none) and every attempt judged; stops at an attempt failing a check
    no tempo changes (:func:`~.attempt.tempo_proof`)."""
    tried: list[Attempt] = []
    for k in factors:
        motion = retime(base.motion, robot, k, human_frames)
        a = Attempt(base.legs, k, motion, judge(motion), retime_of=base.factor)
        tried.append(a)
        if a.feasible:
            return a, tried
        if set(a.failed()) & tempo_proof(motion):
            break
    return None, tried

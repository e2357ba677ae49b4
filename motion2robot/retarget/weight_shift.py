"""Can the whole body shift its weight in time? A screen run before the whole-body attempts.

The whole-body pipeline balances statically: its pinned solve keeps the CoM over the soles that
are down, so before a foot lifts the CoM must already stand over the other one. It gets there
during the double support before the lift-off. Moving the CoM by ``D`` in a time ``tau`` along a
minimum-jerk path peaks at an acceleration ``5.77 D / tau^2``, and a CoM at height ``h``
accelerating at ``a`` puts the ZMP ``a h / g`` ahead of it, which must stay on the soles. So the
shift takes at least ``tau_min = sqrt(5.77 D h / (g w))``, generously: ``D`` is only how far the
CoM must go to reach the stance sole's inner edge (half the distance between the feet less half
the sole's width) and ``w`` is the sole's whole width (the ZMP allowed to its outer edge). A clip
whose human lifts a foot after less double support than ``tau_min``, even slowed to the tempo cap,
asks the whole body for a jump of the CoM at that lift-off: every solve and check of it is spent
for nothing. On the dev clips every clip that lifts a foot at all failed the whole body at x1.0
and at x2.5 (every clip that does not passed it, or failed the playback only); the screen stops
28 of them and lets 9 through. A human walk whose heel-up frames leave no double support at all
asks for the jump at every step.

Units: metres, seconds; labels (T, 2) [left, right]; z up.
"""

from __future__ import annotations

import mujoco
import numpy as np

from motion2robot.motion.human import KP, HumanMotion
from motion2robot.retarget.contacts import phases, planted
from motion2robot.retarget.scale import auto_scale, scaled_keypoints
from motion2robot.retarget.zmp_plan import GRAVITY
from motion2robot.robot.robot import Robot

#: Peak acceleration of a minimum-jerk move over distance D in time tau is PEAK * D / tau^2.
PEAK = 5.77


def _geometry(robot: Robot) -> tuple[float, float]:
    """(CoM height at the nominal posture, sole width), metres; the width from the feet's config."""
    d = robot.new_data()
    mujoco.mj_comPos(robot.model, d)
    width = 2.0 * min(f.sole_half[1] for f in robot.config.feet)
    return float(d.subtree_com[robot.root_body][2]), float(width)


def _shift_time(distance: float, height: float, width: float) -> float:
    if distance <= 0.0:
        return 0.0
    return float(np.sqrt(PEAK * distance * height / (GRAVITY * max(width, 1e-3))))


def shift_time(robot: Robot, distance: float) -> float:
    """s: the shortest static weight shift of ``distance`` (m, from between the feet to the stance
    sole's inner edge) on ``robot`` (its nominal CoM height, its sole's width; see the module text)."""
    return _shift_time(distance, *_geometry(robot))


def short_shifts(human: HumanMotion, robot: Robot, labels: np.ndarray, cap: float) -> str | None:
    """None, or why the whole body cannot balance ``human`` (contact ``labels`` (T, 2)) at any tempo
    up to ``cap``: its first lift-off whose double support, slowed ``cap`` times, is shorter than
    the weight shift it needs."""
    feet = planted(labels, human)
    kp = scaled_keypoints(human.positions, auto_scale(human, robot))
    ankles = kp[:, [KP["left_ankle"], KP["right_ankle"]], :2]
    both = feet.all(axis=1)
    height, width = _geometry(robot)
    for f, a, e in sorted(phases(feet), key=lambda r: r[2]):
        if e >= len(feet) or not labels[e - 1, 1 - f]:
            continue  # the clip ends standing, or the other foot is off the floor (flight: not this screen's)
        n = 0
        while n < e and both[e - 1 - n]:
            n += 1
        distance = 0.5 * float(np.linalg.norm(ankles[e - 1, 0] - ankles[e - 1, 1]) - width)
        need = _shift_time(distance, height, width)
        if cap * n / human.fps < need:
            side = ("left", "right")[f]
            return (f"at {e / human.fps:.2f} s the {side} foot lifts after {1000 * n / human.fps:.0f} ms with both "
                    f"soles flat on the floor; balanced statically, {robot.name} needs {1000 * need:.0f} ms to shift "
                    f"its weight {100 * distance:.1f} cm onto the other foot (x{cap:g} gives "
                    f"{1000 * cap * n / human.fps:.0f} ms)")
    return None

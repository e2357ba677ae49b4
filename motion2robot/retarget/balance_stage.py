"""The dynamic-balance stage: the multi-body ZMP brought inside the soles by a planned CoM path.

Up to ZMP_ROUNDS rounds of: measure the multi-body ZMP of the trajectory, plan a CoM shift by the
cart-table QP (:mod:`~motion2robot.retarget.zmp_plan`), pin the CoM to the shifted path and
project the trajectory onto it and the other hard constraints. Kept only if it brings the ZMP
closer to the soles without leaving any hard constraint (contacts, floor, self-collision)
violated; otherwise the trajectory is returned as it came (``applied`` False). Skipped when the
ZMP is beyond ZMP_REACH sole lengths outside: spikes of a motion that fast are not a CoM shift away.

Units: metres, seconds.
"""

from __future__ import annotations

import numpy as np

from motion2robot.retarget.constraints import clamp_velocity, support_margin
from motion2robot.retarget.contact_plan import ContactPlan
from motion2robot.retarget.setup import Setup
from motion2robot.retarget.solve_stages import EXTRA_CORRECTIONS
from motion2robot.retarget.solver import EXTRA_TOLERANCE, correct
from motion2robot.retarget.zmp_plan import MIN_SHIFT, cart_table_shift, com_boxes, multibody_zmp

#: Rounds of the ZMP planning stage at most.
ZMP_ROUNDS = 2
#: The ZMP planning stage is tried when the ZMP leaves the soles by at most this many sole lengths.
ZMP_REACH = 2.0


def dynamic_balance(setup: Setup, plan: ContactPlan, Q: np.ndarray) -> tuple[np.ndarray, dict]:
    """The trajectory after the stage, and its figures (applied, rounds, max_shift_m,
    zmp_outside_before_m / _after_m, skipped)."""
    robot, fps, planes, support = setup.robot, setup.fps, plan.planes, plan.support

    def outside(zmp: np.ndarray) -> float:
        return float(np.max(np.maximum(0.0, -support_margin(np.nan_to_num(zmp), planes)) * support, initial=0.0))

    figures = {"applied": False, "rounds": 0, "max_shift_m": 0.0}
    Q0 = Q
    zmp, com = multibody_zmp(Q, fps, robot)
    figures["zmp_outside_before_m"] = before = outside(zmp)
    reach = ZMP_REACH * 2.0 * max(max(f.sole_half) for f in robot.config.feet)
    if before > reach:
        figures["zmp_outside_after_m"] = before
        figures["skipped"] = f"the ZMP is {before:.2f} m outside the soles, beyond {reach:.2f} m"
        return Q, figures
    for _ in range(ZMP_ROUNDS):
        d, _ = cart_table_shift(zmp, com[:, 2], planes, support, fps)
        if np.abs(d).max() < MIN_SHIFT:
            break
        P3 = plan.params(setup, planes=com_boxes(com[:, :2] + d, support, planes))
        Q, _ = correct(setup.problem, P3, Q, robot.lower, robot.upper, setup.max_step, 2, extra=EXTRA_CORRECTIONS)
        Q[:, 7:] = clamp_velocity(Q[:, 7:], robot.velocity_limit, fps)
        figures["rounds"] += 1
        figures["max_shift_m"] = max(figures["max_shift_m"], float(np.abs(d).max()))
        zmp, com = multibody_zmp(Q, fps, robot)
    figures["zmp_outside_after_m"] = after = outside(zmp)
    if figures["rounds"] and after < before:  # the other hard rows (no CoM boxes) must hold as before
        P_plain = plan.params(setup, balance=False)
        if float(np.max(setup.problem.violation_eval(len(Q))(Q, P_plain)[0], initial=0.0)) <= EXTRA_TOLERANCE:
            figures["applied"] = True
            return Q, figures
    figures["zmp_outside_after_m"] = before
    return Q0, figures

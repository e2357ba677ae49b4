"""The whole-body screen: a lift-off with too little double support for a static weight shift,
even at the tempo cap, is said and the whole body not tried; a motion that stands is tried."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.motion import read_motion
from motion2robot.retarget import RetargetOptions, retarget
from motion2robot.retarget.contacts import contact_labels
from motion2robot.retarget.weight_shift import shift_time, short_shifts
from motion2robot.robot import load_robot
from tests._shared import MOTIONS, requires_shared


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def test_a_longer_shift_takes_longer_and_none_takes_no_time(op3):
    times = [shift_time(op3, d) for d in (0.0, 0.01, 0.02, 0.04)]
    assert times[0] == 0.0 and shift_time(op3, -0.01) == 0.0
    assert np.all(np.diff(times) > 0)
    assert times[2] == pytest.approx(np.sqrt(2.0) * times[1])  # tau grows as sqrt(D)
    assert 0.1 < times[3] < 0.5  # op3: a few tenths of a second for its half stance width


@requires_shared
def test_a_quick_step_is_screened_and_a_bow_is_not(op3):
    """MDM's throw #10 lifts the right foot 50 ms after both soles are flat: no tempo up to x2.5
    gives op3 the time to shift its weight, and the reason names the frame, the times and the
    distance; the Bandai bow never lifts a foot."""
    throw = read_motion(MOTIONS / "mdm_results" / "mdm_throw_ball_results.npy", clip=10)[0]
    why = short_shifts(throw, op3, contact_labels(throw)[0], 2.5)
    assert why is not None and "right foot lifts after 50 ms" in why and "x2.5 gives 125 ms" in why
    # a cap slow enough for the shift lets the whole body be tried
    assert short_shifts(throw, op3, contact_labels(throw)[0], 10.0) is None
    bow = read_motion(MOTIONS / "bvh" / "bandai_bow_normal_001.bvh")[0]
    assert short_shifts(bow, op3, contact_labels(bow)[0], 2.5) is None


@requires_shared
def test_the_policy_says_why_the_whole_body_was_not_tried(op3):
    throw = read_motion(MOTIONS / "mdm_results" / "mdm_throw_ball_results.npy", clip=10)[0]
    motion = retarget(throw, op3)
    assert all(a["legs"] != "whole" for a in motion.meta["attempts"])
    assert motion.meta["legs_skipped"][0]["legs"] == "whole"
    assert motion.meta["fallback"]["why"].startswith("the whole body not tried: at 1.60 s the right foot lifts")
    # asked for, the whole body is still solved (and judged)
    asked = retarget(throw, op3, RetargetOptions(legs="whole"))
    assert [a["legs"] for a in asked.meta["attempts"]][0] == "whole"

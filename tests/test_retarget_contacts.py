"""Contact phases, and which of their frames a flat robot sole is planted in (not while the
human's heel is up: landing, toe-off)."""

from __future__ import annotations

import numpy as np

from motion2robot.motion.human import KP, HumanMotion
from motion2robot.retarget.contacts import HEEL_LIFT, anchor_soles, phases, planted


def _human(left_ankle_z: np.ndarray) -> HumanMotion:
    T = len(left_ankle_z)
    pos = np.zeros((T, 22, 3))
    pos[:, :, 2] = 0.5
    pos[:, KP["left_ankle"], 2] = left_ankle_z
    pos[:, KP["right_ankle"], 2] = 0.08
    return HumanMotion(pos, 30.0)


def test_phases_are_runs_per_foot():
    labels = np.array([[1, 0], [1, 1], [0, 1], [1, 1]], dtype=bool)
    assert sorted(phases(labels)) == [(0, 0, 2), (0, 3, 4), (1, 1, 4)]


def test_heel_up_frames_at_the_ends_of_a_phase_are_not_planted():
    # left ankle: landing from 5 cm, flat at 8 cm, then the heel rises (toe-off) while labelled in contact
    z = np.array([0.13, 0.11, 0.095, 0.085, 0.08, 0.08, 0.081, 0.08, 0.09, 0.11, 0.14, 0.17])
    labels = np.ones((len(z), 2), dtype=bool)
    out = planted(labels, _human(z))
    up = z - z.min() > HEEL_LIFT
    assert not out[up, 0].any()                       # 0.13/0.11 at landing, 0.11-0.17 at toe-off
    assert out[~up, 0].all() and out[2:9, 0].all()    # the flat frames stay planted
    assert out[:, 1].all()                            # the right heel never rises


def test_heel_up_in_the_middle_of_a_phase_is_kept_and_a_phase_keeps_its_lowest_frame():
    z = np.array([0.08, 0.08, 0.12, 0.08, 0.08])          # a mid-phase bump: not an end, stays planted
    labels = np.zeros((5, 2), dtype=bool)
    labels[:, 0] = True
    assert planted(labels, _human(z))[:, 0].all()
    tiptoe = np.array([0.20, 0.19, 0.21])                  # all frames high: the lowest is kept
    labels = np.zeros((3, 2), dtype=bool)
    labels[:, 0] = True
    out = planted(labels, _human(tiptoe))
    assert out[1, 0] and out[:, 0].sum() >= 1


def test_anchor_soles_pins_each_phase_at_its_first_frame():
    T = 4
    corners = np.zeros((T, 2, 4, 3))
    base = np.array([[0.05, 0.02], [0.05, -0.02], [-0.05, 0.02], [-0.05, -0.02]])
    for t in range(T):
        corners[t, :, :, :2] = base + [0.01 * t, 0.0]
    labels = np.array([[0, 0], [1, 0], [1, 0], [0, 0]], dtype=bool)
    soles = anchor_soles(corners, labels)
    assert np.isnan(soles[0]).all() and np.isnan(soles[:, 1]).all()
    assert np.allclose(soles[1, 0, :, :2], base + [0.01, 0.0]) and np.allclose(soles[2, 0], soles[1, 0])
    assert np.allclose(soles[1:3, 0, :, 2], 0.0)

"""Tempo (time stretch, policies) and the stance alternative, on constructed and real motion."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.errors import UserError
from motion2robot.motion import read_motion
from motion2robot.motion.human import KP, HumanMotion
from motion2robot.retarget.stance import UPPER, has_flight, heading, stance
from motion2robot.retarget.tempo import auto_factors, parse_cap, parse_tempo, similar_factor, stretch
from tests._shared import MOTIONS, requires_shared


def _walkish(T=60, fps=20.0, yaw_rate=0.5):
    """A body walking forward along x while turning: every keypoint a fixed offset from the pelvis,
    turned by the heading; the left foot in contact in the first half, the right in the second."""
    rng = np.random.default_rng(0)
    local = rng.normal(0.0, 0.2, size=(22, 3))
    for side, y in (("left", 0.1), ("right", -0.1)):
        local[KP[f"{side}_hip"]] = (0.0, y, -0.05)
        local[KP[f"{side}_knee"]] = (0.05, y, -0.45)
        local[KP[f"{side}_ankle"]] = (0.0, y, -0.83)
        local[KP[f"{side}_foot"]] = (0.12, y, -0.88)
    t = np.arange(T) / fps
    yaw = yaw_rate * t
    c, s = np.cos(yaw), np.sin(yaw)
    R = np.zeros((T, 3, 3))
    R[:, 0, 0], R[:, 0, 1], R[:, 1, 0], R[:, 1, 1], R[:, 2, 2] = c, -s, s, c, 1
    pelvis = np.stack([t, 0.1 * t, 0.9 + 0.02 * np.sin(5 * t)], axis=1)
    pos = pelvis[:, None, :] + np.einsum("tij,kj->tki", R, local)
    contacts = np.zeros((T, 2), bool)
    contacts[: T // 2, 0] = True
    contacts[T // 2:, 1] = True
    return HumanMotion(pos, fps, contacts=contacts, meta={"source": "constructed"}), yaw


def test_stretch_slows_the_motion_down_at_the_same_rate():
    human, _ = _walkish()
    slow = stretch(human, 2.0)
    assert slow.fps == human.fps
    assert slow.num_frames == 2 * (human.num_frames - 1) + 1
    np.testing.assert_allclose(slow.positions[::2], human.positions, atol=1e-12)  # through every sample
    assert slow.contacts[: 2 * (human.num_frames // 2) - 1, 0].all()
    v = np.abs(np.diff(human.positions, axis=0)).max()
    assert np.abs(np.diff(slow.positions, axis=0)).max() < 0.6 * v
    assert slow.meta["tempo"] == 2.0
    assert stretch(human, 1.0) is human


def test_tempo_values_are_checked():
    assert parse_tempo("auto") == "auto" and parse_tempo(" Human ") == "human" and parse_tempo("1.5") == 1.5
    for bad in ("0", "-1", "nan", "inf", "fast", "100"):
        with pytest.raises(UserError, match="--tempo"):
            parse_tempo(bad)
    assert parse_cap("2.5") == 2.5
    for bad in ("0.5", "nan", "x"):
        with pytest.raises(UserError, match="--tempo-cap"):
            parse_cap(bad)
    assert auto_factors(2.5) == [1.0, 1.25, 1.6, 2.0, 2.5]
    assert auto_factors(1.0) == [1.0]
    # dynamically similar: Froude number kept, durations x sqrt(s)
    assert similar_factor(0.25) == pytest.approx(0.5)


def test_heading_follows_the_hips():
    human, yaw = _walkish()
    np.testing.assert_allclose(heading(human.positions), yaw, atol=1e-9)


def test_stance_keeps_the_upper_body_relative_to_the_pelvis_and_plants_the_feet():
    human, yaw = _walkish()
    st = stance(human)
    P, H = st.positions, human.positions
    # the pelvis stands still at its first position and the clip's heading at frame 0
    assert np.ptp(P[:, KP["pelvis"]], axis=0).max() < 1e-12
    np.testing.assert_allclose(P[0, KP["pelvis"], :2], H[0, KP["pelvis"], :2])
    # the feet stand still on the floor, both in contact in every frame
    for k in ("left_ankle", "right_ankle", "left_foot", "right_foot", "left_knee", "right_knee"):
        assert np.ptp(P[:, KP[k]], axis=0).max() < 1e-12
    assert st.contacts.all()
    # upper body: its motion relative to the pelvis, turned by the pelvis's own heading
    for name in UPPER:
        rel_h = H[:, KP[name]] - H[:, KP["pelvis"]]
        rel_s = P[:, KP[name]] - P[:, KP["pelvis"]]
        d = yaw - yaw[0]
        c, s = np.cos(-d), np.sin(-d)
        back = np.stack([c * rel_h[:, 0] - s * rel_h[:, 1], s * rel_h[:, 0] + c * rel_h[:, 1], rel_h[:, 2]], axis=1)
        np.testing.assert_allclose(rel_s, back, atol=1e-9)
    # the legs keep their lengths
    for hip, knee, ankle in (("left_hip", "left_knee", "left_ankle"), ("right_hip", "right_knee", "right_ankle")):
        for a, b in ((hip, knee), (knee, ankle)):
            np.testing.assert_allclose(np.linalg.norm(P[:, KP[a]] - P[:, KP[b]], axis=1),
                                       np.median(np.linalg.norm(H[:, KP[a]] - H[:, KP[b]], axis=1)), atol=1e-6)


def test_flight_detection():
    labels = np.array([[1, 1], [1, 0], [0, 0], [0, 0], [0, 1], [1, 1]], bool)
    human = HumanMotion(np.zeros((6, 22, 3)), 20.0)
    assert has_flight(human, labels)
    labels[3] = [1, 0]
    assert not has_flight(human, labels)  # one frame off both feet is a fast walk's double float, not a run
    assert not has_flight(human, np.ones((6, 2), bool))


@requires_shared
def test_stance_of_a_real_walk_is_quasi_static():
    human = read_motion(MOTIONS / "bvh" / "bandai_walk_normal_001.bvh")[0]
    st = stance(human)
    pelvis = st.positions[:, KP["pelvis"]]
    assert np.ptp(pelvis, axis=0).max() < 1e-9
    feet = st.positions[:, [KP["left_foot"], KP["right_foot"]], 2]
    assert feet.min() >= -1e-9 and feet.max() < 0.05  # toes on the floor
    wrist = st.positions[:, KP["left_wrist"]] - pelvis
    assert np.linalg.norm(wrist, axis=1).max() < 1.0  # the arms swing beside the body, not 8 m away

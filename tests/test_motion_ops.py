"""Operations on HumanMotion and contact detection (agreement with the 263-d labels)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2robot.motion import (KP, HumanMotion, align_floor, align_heading, detect_contacts, mirror,
                                 read_motion, resample, subject_height, trim, with_contacts)
from motion2robot.motion.canonical import rot_z
from motion2robot.motion.ops import catmull_rom, facing_yaw, rotate_heading
from tests._shared import MOTIONS, requires_shared
from tests.test_motion_support import walking_yup


def _walk(frames: int = 40, fps: float = 20.0) -> HumanMotion:
    yup = walking_yup(frames, fps)
    pos = np.stack([yup[..., 2], yup[..., 0], yup[..., 1]], axis=-1)  # canonical: x fwd, y left, z up
    pos[..., 2] -= pos[:, [7, 8, 10, 11], 2].min()
    c = np.zeros((frames, 2), bool)
    c[::3, 0] = True
    return HumanMotion(pos, fps, contacts=c, meta={"source": "synthetic"})


def test_cubic_resample_passes_through_original_frames() -> None:
    m = _walk(41)
    up = resample(m, 40.0)
    assert up.num_frames == 81 and up.fps == 40.0
    np.testing.assert_allclose(up.positions[::2], m.positions, atol=1e-12)
    assert (up.contacts[::2] == m.contacts).all()  # nearest frame
    back = resample(up, 20.0, kind="linear")
    np.testing.assert_allclose(back.positions, m.positions, atol=1e-12)
    assert back.meta["resampled_from_fps"] == 40.0


def test_cubic_is_exact_on_cubics_and_smoother_than_linear() -> None:
    t = np.arange(10.0)
    u = np.linspace(1, 8, 50)  # away from the extrapolated ends
    np.testing.assert_allclose(catmull_rom((t ** 2)[:, None], u)[:, 0], u ** 2, atol=1e-9)
    m = _walk(40)
    s = resample(m, 30.0)
    assert s.num_frames == int(39 * 30 / 20) + 1
    with pytest.raises(ValueError):
        resample(m, 0.0)
    with pytest.raises(ValueError):
        resample(m, 30.0, kind="quintic")


def test_trim() -> None:
    m = _walk(40)
    t = trim(m, 5, 15)
    assert t.num_frames == 10 and np.array_equal(t.positions, m.positions[5:15])
    assert np.array_equal(t.contacts, m.contacts[5:15]) and t.meta["trimmed"] == [5, 15]
    assert trim(m, -10).num_frames == 10
    with pytest.raises(ValueError, match="at least 2"):
        trim(m, 39, 40)


def test_floor_and_heading_alignment_undo_a_rigid_move() -> None:
    m = _walk(40)
    moved = m.with_(positions=m.positions @ rot_z(1.1).T + [3.0, -2.0, 0.4])
    assert facing_yaw(moved) == pytest.approx(1.1)
    assert align_floor(moved).positions[:, [7, 8, 10, 11], 2].min() == pytest.approx(0.0)
    back = align_heading(moved)
    np.testing.assert_allclose(back.positions, m.positions - [m.positions[0, 0, 0], m.positions[0, 0, 1], 0], atol=1e-9)
    assert facing_yaw(rotate_heading(m, 0.5)) == pytest.approx(0.5)


def test_mirror_swaps_sides_and_is_an_involution() -> None:
    m = _walk(40)
    mm = mirror(m)
    np.testing.assert_allclose(mm.positions[:, KP["left_hip"], 1], -m.positions[:, KP["right_hip"], 1])
    assert (mm.contacts[:, 0] == m.contacts[:, 1]).all()
    assert facing_yaw(mm) == pytest.approx(0.0, abs=1e-9)  # still faces +x
    np.testing.assert_allclose(mirror(mm).positions, m.positions)
    assert mirror(mm).meta["mirrored"] is False


@requires_shared
def test_mirrored_dataset_clip_mirrors_back() -> None:
    """M010968 is the data set's mirror of a clip: mirroring it keeps a valid, same-height body."""
    m = read_motion(MOTIONS / "humanml3d_joints" / "M010968.npy")[0]
    mm = mirror(m)
    assert subject_height(mm) == pytest.approx(subject_height(m))
    # the raised arm switches side
    raise_l = m.positions[:, KP["left_wrist"], 2].max() - mm.positions[:, KP["left_wrist"], 2].max()
    raise_r = m.positions[:, KP["right_wrist"], 2].max() - mm.positions[:, KP["right_wrist"], 2].max()
    assert raise_l * raise_r < 0


@requires_shared
@pytest.mark.parametrize("name", ["007005", "011673", "012314", "M010968"])
def test_detected_contacts_agree_with_263d_labels(name: str) -> None:
    m = read_motion(MOTIONS / "humanml3d_vecs" / f"{name}.npy")[0]
    agree = (detect_contacts(m) == m.contacts).mean()
    # measured with the defaults (0.15 m, 0.6 m/s): 007005 93.5 %, 011673 96.0 %,
    # 012314 96.2 %, M010968 100 %; 95.7 % over all foot-frames
    assert agree >= 0.90, agree


def test_detect_contacts_on_a_synthetic_step() -> None:
    fps = 50.0
    t = np.arange(100) / fps
    base = _walk(100, fps).positions.copy()
    base[..., 0] -= base[:, :1, 0]  # stand in place
    lift = np.where((t > 0.5) & (t < 1.0), 0.3 * np.sin(np.pi * (t - 0.5) / 0.5), 0.0)
    base[:, [KP["left_ankle"], KP["left_foot"]], 2] += lift[:, None]
    c = detect_contacts(HumanMotion(base, fps))
    assert c[:, 1].all()  # right foot never moves
    assert not c[(t > 0.65) & (t < 0.85), 0].any() and c[t < 0.4, 0].all() and c[t > 1.1, 0].all()


def test_with_contacts_keeps_labels_and_fills_missing() -> None:
    m = _walk(40)
    assert with_contacts(m).contacts is not None and with_contacts(m).meta["contacts_source"] == "file"
    bare = HumanMotion(m.positions, m.fps)
    filled = with_contacts(bare)
    assert filled.contacts.shape == (40, 2) and filled.meta["contacts_source"].startswith("detected")


def test_spline_is_c2_through_the_samples():
    """The resampling spline passes through every sample and its curvature does not jump at them
    (Catmull-Rom's does: a finer rate then shows acceleration spikes at the original frames)."""
    from motion2robot.motion.ops import spline

    rng = np.random.default_rng(3)
    v = np.cumsum(rng.standard_normal((12, 2)), axis=0)
    np.testing.assert_allclose(spline(v, np.arange(12.0)), v, atol=1e-12)
    h = 1e-3
    for k in range(1, 11):                                  # second derivative from both sides of knot k
        left = (spline(v, np.array([k - 2 * h]))[0] - 2 * spline(v, np.array([k - h]))[0] + spline(v, np.array([k]))[0]) / h**2
        right = (spline(v, np.array([k]))[0] - 2 * spline(v, np.array([k + h]))[0] + spline(v, np.array([k + 2 * h]))[0]) / h**2
        np.testing.assert_allclose(left, right, atol=1e-2)

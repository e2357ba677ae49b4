"""The exact final root pass (floor, stance sole pinned), the separation of the feet's anchors and
the self-collision capsules that contain their boxes."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from motion2robot.retarget import RetargetOptions, whole_body as retarget
from motion2robot.retarget.anchor_gap import foot_capsules, segment_distance, separate_anchors
from motion2robot.retarget.collision import body_capsules
from motion2robot.retarget.metrics import acceptance
from motion2robot.retarget.root_pass import foot_yaw, root_shift
from motion2robot.robot import load_robot
from tests._shared import MOTIONS, requires_shared


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def _sole(centre_xy, z, yaw: float = 0.0) -> np.ndarray:
    """(4, 3) corners of a 0.1 x 0.05 m sole at ``centre_xy``, height ``z`` (m), turned by ``yaw``
    (rad) about the vertical."""
    off = np.array([[0.05, 0.025], [0.05, -0.025], [-0.05, -0.025], [-0.05, 0.025]])
    c, s = np.cos(yaw), np.sin(yaw)
    out = np.zeros((4, 3))
    out[:, :2] = np.asarray(centre_xy) + off @ np.array([[c, s], [-s, c]])
    out[:, 2] = z
    return out


def test_root_shift_constructed_single_and_double_support():
    """Left foot in contact for frames 0-5 while sliding forward 1 cm per frame and sinking; the
    right foot swings (and dips below the floor in frame 7), then lands (frames 8-11) while
    sliding backwards. After the shift: no corner below z = 0 anywhere, each stance sole keeps
    its place while it is the only continuing contact, and contact frames touch the floor."""
    T = 12
    corners = np.zeros((T, 2, 4, 3))
    labels = np.zeros((T, 2), dtype=bool)
    labels[:6, 0] = True
    labels[8:, 1] = True
    for t in range(T):
        corners[t, 0] = _sole((0.01 * t, 0.05), -0.002 * t if t < 6 else 0.03)
        corners[t, 1] = _sole((0.05 * t, -0.05), {6: 0.02, 7: -0.004}.get(t, 0.0) - 0.001 * (t >= 8))
        if t >= 8:
            corners[t, 1, :, 0] -= 0.005 * (t - 8)
    out = root_shift(corners, labels, fps=20.0)
    moved = corners + out.shift[:, None, None, :]
    assert moved[..., 2].min() >= -1e-12                                   # floor, every frame
    low = moved[..., 2].min(axis=(1, 2))
    assert np.allclose(low[labels.any(axis=1)], 0.0, atol=1e-12)          # contact frames touch it
    centre = moved[..., :2].mean(axis=2)
    assert np.allclose(np.diff(centre[:6, 0], axis=0), 0.0, atol=1e-12)    # left pinned
    assert np.allclose(np.diff(centre[8:, 1], axis=0), 0.0, atol=1e-12)    # right pinned
    assert set(out.pinned[1:6]) == {0} and set(out.pinned[9:]) == {1}
    assert out.figures()["max_root_shift_m"] > 0.0


def test_double_support_pins_the_older_foot_or_shares_a_small_slide():
    T = 6
    labels = np.ones((T, 2), dtype=bool)
    labels[:2, 1] = False                                                   # right lands at frame 2
    corners = np.zeros((T, 2, 4, 3))
    for t in range(T):
        corners[t, 0] = _sole((0.0, 0.05), 0.0)
        corners[t, 1] = _sole((0.2 + 0.02 * t, -0.05), 0.0)                # right slides 2 cm/frame
    out = root_shift(corners, labels, fps=20.0)
    centre = (corners + out.shift[:, None, None, :])[..., :2].mean(axis=2)
    assert np.allclose(np.diff(centre[:, 0], axis=0), 0.0, atol=1e-12)     # the older (left) stays
    # a relative slide within twice the tolerance is shared: both feet under 1 cm/s
    for t in range(T):
        corners[t, 1] = _sole((0.2 + 0.0008 * t, -0.05), 0.0)              # 1.6 cm/s relative
    out = root_shift(corners, labels, fps=20.0)
    centre = (corners + out.shift[:, None, None, :])[..., :2].mean(axis=2)
    speed = np.linalg.norm(np.diff(centre, axis=0), axis=-1) * 20.0
    assert speed[2:].max() < 0.01 and (out.pinned[3:] == 2).all()


def _spinning_walk(T: int = 14) -> tuple[np.ndarray, np.ndarray]:
    """A rigid robot (both soles, the root) turning by 0.1 rad per frame about a vertical axis at
    (0.3, 0.2) while drifting 1 cm per frame in x: left foot in contact in frames 0-6, right in
    frames 8-13, nothing in frame 7."""
    labels = np.zeros((T, 2), dtype=bool)
    labels[:7, 0] = True
    labels[8:, 1] = True
    corners = np.zeros((T, 2, 4, 3))
    axis = np.array([0.3, 0.2])
    for t in range(T):
        a = 0.1 * t
        rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        for f, y in ((0, 0.05), (1, -0.05)):
            centre = axis + rot @ (np.array([0.0, y]) - axis) + [0.01 * t, 0.0]
            corners[t, f] = _sole(centre, 0.0, a)
    return corners, labels


def test_stance_foot_keeps_its_yaw_and_corners_in_single_support():
    corners, labels = _spinning_walk()
    assert np.ptp(foot_yaw(corners)[:7, 0]) > 0.5                           # it does spin before the pass
    out = root_shift(corners, labels, fps=20.0, yaw_slide=0.0)
    moved = out.points(corners)
    yaw = foot_yaw(moved)
    for f, frames in ((0, slice(0, 7)), (1, slice(8, 14))):
        assert np.ptp(yaw[frames, f]) < 1e-6                                # yaw constant in contact
        assert np.abs(np.diff(moved[frames, f], axis=0)).max() < 1e-9       # corners do not move
    assert moved[..., 2].min() >= -1e-12
    # the root itself: the quaternion turns by the yaw, the position with the bodies
    qpos = np.zeros((len(labels), 9))
    qpos[:, 3] = 1.0
    qpos[:, :3] = corners[:, 0].mean(axis=1)                                # a "root" at the left sole centre
    q = out.apply(qpos)
    assert np.allclose(q[:, :3], moved[:, 0].mean(axis=1), atol=1e-12)
    assert np.allclose(q[:, 3], np.cos(out.yaw / 2)) and np.allclose(q[:, 6], np.sin(out.yaw / 2))
    assert np.allclose(np.linalg.norm(q[:, 3:7], axis=1), 1.0)
    assert abs(out.yaw.mean()) < 1e-9                                       # no net heading offset
    assert out.figures()["max_root_yaw_rad"] > 0.3


def test_double_support_shares_a_common_turn_and_keeps_a_relative_one():
    """Both feet in contact: a common turn of the pair (the whole robot spinning) is undone for
    both; a relative turn of one foot (the joints) leaves the root's yaw alone."""
    T = 8
    labels = np.ones((T, 2), dtype=bool)
    corners = np.zeros((T, 2, 4, 3))
    for t in range(T):
        a = 0.05 * t
        rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        corners[t, 0] = _sole(rot @ [0.0, 0.05], 0.0, a)
        corners[t, 1] = _sole(rot @ [0.0, -0.05], 0.0, a)
    out = root_shift(corners, labels, fps=20.0, yaw_slide=0.0)
    assert np.abs(np.diff(out.points(corners), axis=0)).max() < 1e-9        # both feet still
    for t in range(T):
        corners[t, 0] = _sole((0.0, 0.05), 0.0, 0.0)
        corners[t, 1] = _sole((0.0, -0.05), 0.0, 0.05 * t)                  # right turns alone
    out = root_shift(corners, labels, fps=20.0, yaw_slide=0.0)
    assert np.abs(out.yaw).max() < 1e-12


def test_yaw_slide_bounds_the_drift_at_a_bounded_corner_speed():
    """A foot spinning steadily for 3 s: the exact correction grows with the spin; with a slide
    budget it stays smaller, and the held sole's corners move at most at that budget."""
    T, fps = 60, 20.0
    labels = np.zeros((T, 2), dtype=bool)
    labels[:, 0] = True
    corners = np.zeros((T, 2, 4, 3))
    for t in range(T):
        corners[t, 0] = _sole((0.0, 0.05), 0.0, 0.02 * t)
        corners[t, 1] = _sole((0.0, -0.05), 0.05, 0.02 * t)
    exact = root_shift(corners, labels, fps, yaw_slide=0.0)
    slack = root_shift(corners, labels, fps, yaw_slide=0.005)
    assert np.ptp(slack.yaw) < np.ptp(exact.yaw) - 0.1
    speed = np.linalg.norm(np.diff(slack.points(corners)[:, 0, :, :2], axis=0), axis=-1) * fps
    assert speed.max() <= 0.005 + 1e-9 and speed.max() > 0.004


def test_anchor_separation_moves_the_later_phase_out_of_the_older_foot():
    T = 10
    labels = np.zeros((T, 2), dtype=bool)
    labels[:, 0] = True
    labels[4:, 1] = True
    anchors = np.full((T, 2, 4, 3), np.nan)
    anchors[:, 0] = _sole((0.0, 0.0), 0.0)
    anchors[4:, 1] = _sole((0.0, -0.03), 0.0)                               # overlaps the left sole
    local = np.array([[[-0.05, 0.0], [0.05, 0.0]]] * 2)
    radius = np.array([0.025, 0.025])
    out, pushed = separate_anchors(anchors, labels, local, radius, 0.004)
    assert np.array_equal(out[:, 0], anchors[:, 0])                         # the older foot is kept
    c = out[4:, 1, :, :2].mean(axis=1)
    assert np.allclose(c, c[0])                                             # one rigid move per phase
    seg_l = np.array([[-0.05, 0.0], [0.05, 0.0]])
    seg_r = c[0] + local[1]
    assert segment_distance(seg_r[0], seg_r[1], seg_l[0], seg_l[1]) >= 0.054 - 1e-9
    assert 0.0 < pushed < 0.03


def test_containing_capsules_hold_every_box_corner(op3):
    m = op3.model
    caps = body_capsules(m, contain=True)
    for g in range(m.ngeom):
        b = int(m.geom_bodyid[g])
        if m.geom_type[g] != mujoco.mjtGeom.mjGEOM_BOX or b not in caps:
            continue
        c = caps[b]
        rot = np.array(m.geom_quat[g])
        mat = np.zeros(9)
        mujoco.mju_quat2Mat(mat, rot)
        half = m.geom_size[g]
        pts = m.geom_pos[g] + (np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half) @ mat.reshape(3, 3).T
        d = segment_distance(pts, pts, c.p0, c.p1)
        assert d.max() <= c.radius + 1e-9, (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b), d.max(), c.radius)


def test_foot_capsules_of_op3(op3):
    local, radius = foot_capsules(op3)
    assert local.shape == (2, 2, 2) and np.all(radius > 0.01)


@requires_shared
def test_walk_clip_floor_and_stance_pinned(op3):
    from motion2robot.motion import read_motion

    human = read_motion(MOTIONS / "bvh" / "bandai_walk_normal_001.bvh")[0]
    out = retarget(human, op3, RetargetOptions(balance=False, hold_stance_yaw=True))
    q = out.qpos
    d = mujoco.MjData(op3.model)
    corners = np.zeros((len(q), 2, 4, 3))
    for t in range(len(q)):
        d.qpos[:] = q[t]
        mujoco.mj_kinematics(op3.model, d)
        corners[t] = d.site_xpos[op3.sole_sites.ravel()].reshape(2, 4, 3)
    assert corners[..., 2].min() >= -1e-9                                   # no corner below the floor
    labels = np.asarray(out.meta["contacts"], dtype=bool)
    single = (labels[1:] & labels[:-1]).sum(axis=1) == 1
    single &= labels[1:].sum(axis=1) == 1
    assert single.sum() > 20
    centre = corners[..., :2].mean(axis=2)
    foot = np.argmax(labels[1:], axis=1)
    step = np.linalg.norm(centre[1:, :][np.arange(len(foot)), foot] - centre[:-1][np.arange(len(foot)), foot], axis=-1)
    assert step[single].max() < 1e-6                                        # stance sole pinned (m/frame)
    # the stance foot does not spin either: its corners stay within 1 cm/s in continuing contact
    rows = np.flatnonzero(single)
    corner_speed = np.linalg.norm(corners[rows + 1, foot[rows], :, :2] - corners[rows, foot[rows], :, :2], axis=-1).max(axis=1) * out.fps
    assert len(rows) > 100 and (corner_speed <= 0.01).mean() >= 0.99
    a = acceptance(out, op3, collisions=False)
    assert a["limit_violations"] == 0 and a["speed_ratio"] <= 1.0 + 1e-9
    assert a["sole_depth_mm"] <= 2.0 and a["contact_slow_pct"] >= 99.0
    rp = out.meta["solver"]["root_pass"]
    assert len(rp["root_shift_per_frame"]) == len(q) and rp["max_root_shift_m"] >= 0.0

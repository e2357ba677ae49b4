"""Every robot motion2robot can find, end to end: the shipped configs (bundled and Menagerie) and a
draft of every humanoid in the Menagerie folder, each loaded, retargeted on one short real clip and
checked (kinematic checks). Drafts are used without edits and their keypoints are judged against
the joint centres the MJCF's joint positions define (``tests/_joint_centres.py``).

Drafting, loading and the keypoint figures run for every robot by default. Retargeting needs each
robot's problem compiled once (10-60 s per robot on a fresh cache, then cached in
``~/.cache/motion2robot``): the bundled op3 runs by default, the others are marked ``slow``
(``pytest -m slow tests/test_robots_discovered.py``).
"""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.robot import load_robot
from motion2robot.robot.draft import draft_config, write_draft
from motion2robot.robot.resolve import bundled_names, menagerie_config_names
from tests._joint_centres import JOINTS, keypoint_errors
from tests._shared import MENAGERIE, MOTIONS, requires_shared

#: mm; a drafted keypoint farther than this from its joint centre fails.
KEYPOINT_TOL_MM = 30.0


def _menagerie_folders() -> list[str]:
    if MENAGERIE is None or not MENAGERIE.is_dir():
        return []
    return sorted(p.name for p in MENAGERIE.iterdir() if p.is_dir() and any(p.glob("*.xml")))


def _case(kind: str, name: str, fast: bool = False):
    marks = [] if fast else [pytest.mark.slow]
    if name.startswith("menagerie:") and not _menagerie_folders():
        marks.append(pytest.mark.skip(reason="no menagerie root"))
    return pytest.param(kind, name, id=f"{kind}-{name.replace(':', '-')}", marks=marks)


CASES = ([_case("shipped", n, fast=True) for n in bundled_names()]
         + [_case("shipped", f"menagerie:{n}") for n in menagerie_config_names()]
         + [_case("draft", n) for n in _menagerie_folders()])


def _draft(name: str, tmp_path):
    draft = draft_config(f"menagerie:{name}", name=f"{name}_draft")
    return draft, load_robot(str(write_draft(draft, tmp_path / f"{name}.toml")))


@pytest.fixture(scope="module")
def clip():
    from motion2robot.motion import read_motion
    from motion2robot.motion.ops import trim

    if MOTIONS is None:
        pytest.skip("../shared (real motion clips) is absent")
    return trim(read_motion(MOTIONS / "humanml3d_joints" / "007005.npy")[0], 40, 52)



def test_every_menagerie_humanoid_is_discovered():
    folders = _menagerie_folders()
    if not folders:
        pytest.skip("no menagerie root")
    assert set(folders) >= {"robotis_op3", "unitree_g1", "unitree_h1"}
    assert set(folders) <= set(JOINTS), f"add the joint centres of {set(folders) - set(JOINTS)} to tests/_joint_centres.py"


@pytest.mark.parametrize("name", _menagerie_folders())
def test_drafted_keypoints_stand_on_their_joint_centres(menagerie_env, tmp_path, name):
    """``robots init`` without edits: the draft loads, stands flat, and every keypoint that stands
    for a joint is within KEYPOINT_TOL_MM of that joint's centre."""
    _, robot = _draft(name, tmp_path)
    d = robot.new_data()
    assert np.all(np.abs(d.site_xpos[robot.sole_sites.ravel(), 2]) < 0.002)
    errors = keypoint_errors(name, robot)
    assert {"pelvis", "left_hip", "right_knee", "left_ankle", "right_shoulder", "left_elbow"} <= set(errors)
    far = {k: round(1000 * v, 1) for k, v in errors.items() if 1000 * v > KEYPOINT_TOL_MM}
    assert not far, f"{name}: drafted keypoints more than {KEYPOINT_TOL_MM} mm from their joint centres: {far}"


@requires_shared
@pytest.mark.parametrize("kind, name", CASES)
def test_robot_end_to_end(menagerie_env, tmp_path, clip, kind, name):
    from motion2robot.retarget import RetargetOptions, retarget
    from motion2robot.validate import check
    from motion2robot.validate.options import CheckOptions

    robot = _draft(name, tmp_path)[1] if kind == "draft" else load_robot(name)
    motion = retarget(clip, robot, RetargetOptions())
    q = motion.qpos[:, 7:]
    assert motion.qpos.shape == (clip.num_frames, robot.nq) and np.isfinite(motion.qpos).all()
    assert np.all(q >= robot.lower - 1e-9) and np.all(q <= robot.upper + 1e-9)
    report = check(motion, robot, CheckOptions(physics=False))
    c = report.checks
    assert c["joint_limits"]["ok"], c["joint_limits"]
    assert not c["ground"].get("penetrations"), c["ground"]["penetrations"]
    assert c["self_collision"]["ok"], c["self_collision"]["violations"]

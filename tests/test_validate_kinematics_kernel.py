"""The compiled frame loop of ``compute_kinematics`` gives the Python loop's numbers, contacts
included (floor and self-collision), with and without the collision pass, and the Python loop
takes over when the contacts do not fit."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.robot import load_robot
from motion2robot.validate import examples, kinematics_kernel
from motion2robot.validate.kinematics import compute_kinematics

FIELDS = ("qpos", "qvel", "qacc", "corners", "corner_vel", "com", "rne", "xanchor", "xaxis", "root_xmat",
          "torso_pos", "torso_up")


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def _same(a, b) -> None:
    for f in FIELDS:
        assert np.array_equal(getattr(a, f), getattr(b, f)), f
    for f in ("frame", "geom1", "geom2", "dist"):
        x, y = getattr(a.contacts, f), getattr(b.contacts, f)
        assert x.dtype == y.dtype and np.array_equal(x, y), f


@pytest.mark.parametrize("collisions", [True, False])
def test_compiled_loop_gives_the_python_loops_numbers(op3, monkeypatch, collisions):
    if kinematics_kernel.library() is None:
        pytest.skip("no C compiler: the Python loop runs")
    motion = examples.arm_through_torso(op3)
    compiled = compute_kinematics(motion, op3, collisions=collisions)
    monkeypatch.setattr(kinematics_kernel, "library", lambda: None)
    python = compute_kinematics(motion, op3, collisions=collisions)
    _same(compiled, python)
    if collisions:  # feet on the floor and the arm in the torso: both kinds of contact were there
        assert len(python.contacts.frame) > 8 * len(motion.qpos)
    else:
        assert len(python.contacts.frame) == 0


def test_more_contacts_than_room_falls_back_to_the_python_loop(op3, monkeypatch):
    if kinematics_kernel.library() is None:
        pytest.skip("no C compiler: the Python loop runs")
    motion = examples.standing(op3, seconds=0.5)
    full = compute_kinematics(motion, op3)
    assert kinematics_kernel.run(*_args(op3, motion)) is not None
    monkeypatch.setattr(kinematics_kernel, "ROOM_PER_FRAME", 1)  # 8 sole corners on the floor per frame
    assert kinematics_kernel.run(*_args(op3, motion)) is None
    _same(compute_kinematics(motion, op3), full)


def _args(robot, motion):
    import mujoco

    from motion2robot.validate.kinematics import differentiate
    from motion2robot.validate.models import check_model

    m = check_model(robot)
    T = len(motion.qpos)
    outs = tuple(np.empty((T, *s)) for s in ((m.nsite, 3), (m.njnt, 3), (m.njnt, 3), (m.nbody, 3), (m.nbody, 3),
                                             (m.nbody, 9), (m.nv,)))
    return (m, mujoco.MjData(m), motion.qpos, *differentiate(motion.qpos, motion.fps), True, outs)

"""The leg tracker's per-frame Levenberg-Marquardt (preallocated, Cholesky on the assembled normal
equations) against a straightforward dense transcription of the same method, on a real walk's
tracking problem; and its generic paths (leg hinges scattered in qpos, overlapping limit zones)
giving the fast paths' numbers."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from motion2robot.motion import read_motion
from motion2robot.motion.ops import trim
from motion2robot.retarget import RetargetOptions, retarget
from motion2robot.retarget import leg_tracker as lt
from motion2robot.retarget import tracker_kernel
from motion2robot.retarget.leg_tracker import LegTracker
from motion2robot.robot import load_robot
from tests._shared import MOTIONS, requires_shared


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


@pytest.fixture(scope="module")
def walk_problem(op3):
    """The arguments of the first ``LegTracker.solve`` of the steps pipeline on 2 s of the Bandai walk."""
    if MOTIONS is None:
        pytest.skip("../shared (real motion clips) is absent")
    calls = []
    solve = LegTracker.solve

    def record(self, *args):
        calls.append(args)
        return solve(self, *args)

    human = trim(read_motion(MOTIONS / "bvh" / "bandai_walk_normal_001.bvh")[0], 0, 60)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(LegTracker, "solve", record)
        retarget(human, op3, RetargetOptions(legs="steps", tempo="1"))
    assert calls
    return calls[0]


def _reference(tr: LegTracker, Q, corners, com_xy, fps, start=None):
    """The tracker's method written out densely: every row stacked, the sole corners' Jacobian from
    the feet's body Jacobians (v + w x arm), the step from ``np.linalg.solve`` on the sub-matrix of
    the free unknowns."""
    m, d, rb = tr.model, mujoco.MjData(tr.model), tr.robot
    nc, n = len(tr.cols), len(tr.legs)
    jp, jr, turn = np.zeros((3, m.nv)), np.zeros((3, m.nv)), np.zeros(3)
    w_prev = lt.TEMPORAL_TIME * fps

    def rows(q, t, prev):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        pos = d.site_xpos[tr.sites]
        J = [np.zeros((26, nc))]
        for f in range(2):
            body = int(rb.foot_bodies[f])
            mujoco.mj_jacBody(m, d, jp, jr, body)
            for i in range(4):
                arm = pos[4 * f + i] - d.xpos[body]
                J[0][12 * f + 3 * i:12 * f + 3 * i + 3] = lt.HARD_WEIGHT * (jp - np.cross(arm, jr.T).T)[:, tr.cols]
        mujoco.mj_jacSubtreeCom(m, d, jp, rb.root_body)
        J[0][24:26] = lt.HARD_WEIGHT * lt.COM_WEIGHT * jp[:2, tr.cols]
        mujoco.mju_subQuat(turn, q[3:7], Q[t, 3:7])
        qj = q[tr.qadr]
        over = np.maximum(qj - (tr.hi - lt.LIMIT_ZONE), 0) - np.maximum(tr.lo + lt.LIMIT_ZONE - qj, 0)
        r = [lt.HARD_WEIGHT * (pos - corners[t].reshape(8, 3)).ravel(),
             lt.HARD_WEIGHT * lt.COM_WEIGHT * (d.subtree_com[rb.root_body, :2] - com_xy[t]),
             [lt.ROOT_HEIGHT_WEIGHT * (q[2] - Q[t, 2])], lt.ROOT_TURN_WEIGHT * turn,
             lt.LIMIT_WEIGHT * np.sign(over) * over ** 2 / lt.LIMIT_ZONE]
        soft = np.zeros((4 + n, nc))
        soft[0, 2], soft[1:4, 3:6] = lt.ROOT_HEIGHT_WEIGHT, lt.ROOT_TURN_WEIGHT * np.eye(3)
        soft[4 + np.arange(n), 6 + np.arange(n)] = 2 * lt.LIMIT_WEIGHT * np.abs(over) / lt.LIMIT_ZONE
        J.append(soft)
        if prev is not None:
            mujoco.mju_subQuat(turn, q[3:7], prev[3:7])
            r += [w_prev * (q[:3] - prev[:3]), w_prev * turn, w_prev * (qj - prev[tr.qadr])]
            J.append(w_prev * np.eye(nc))
        return np.concatenate(r), np.vstack(J)

    out = Q.copy()
    for t in range(len(Q)):
        prev = out[t - 1] if t else None
        q = Q[t].copy()
        if start is not None:
            q[:7], q[tr.qadr] = start[t, :7], start[t, tr.qadr]
        elif t:
            q[:2], q[tr.qadr] = prev[:2], prev[tr.qadr]
        r, J = rows(q, t, prev)
        cost, mu = r @ r, lt.DAMPING
        for _ in range(lt.IK_ITERATIONS):
            free = np.ones(nc, dtype=bool)
            for _ in range(3):
                dx = np.zeros(nc)
                A = J[:, free]
                dx[free] = np.linalg.solve(A.T @ A + mu * np.eye(free.sum()), -A.T @ r)
                qj = q[tr.qadr]
                push = ((qj <= tr.lo + 1e-9) & (dx[6:] < 0)) | ((qj >= tr.hi - 1e-9) & (dx[6:] > 0))
                if not push.any():
                    break
                free[6:] &= ~push
            dx *= min(1.0, lt.MAX_STEP / max(np.abs(dx).max(), 1e-12))
            q_new = q.copy()
            q_new[:3] += dx[:3]
            mujoco.mju_quatIntegrate(q_new[3:7], dx[3:6], 1.0)
            q_new[tr.qadr] = np.clip(q_new[tr.qadr] + dx[6:], tr.lo, tr.hi)
            r_new, J_new = rows(q_new, t, prev)
            if r_new @ r_new < cost:
                done = np.abs(dx).max() < lt.STEP_TOLERANCE or cost - r_new @ r_new < 1e-12 * lt.HARD_WEIGHT ** 2
                q, r, J, cost, mu = q_new, r_new, J_new, r_new @ r_new, max(mu / 10, lt.DAMPING)
                if done:
                    break
            else:
                mu *= 100
        out[t] = q
    return out


@requires_shared
def test_leg_tracker_matches_a_dense_reference_on_a_real_walk(op3, walk_problem):
    """The same trajectory as the dense transcription, to rounding (the per-frame LM's own
    noise floor: a step too small to lower the cost by more than its rounding is kept or not
    depending on the order of the sums), and its targets reached."""
    tr = LegTracker(op3)
    out, err = tr.solve(*walk_problem)
    ref = _reference(tr, *walk_problem)
    assert np.abs(out - ref).max() < 1e-8
    assert err.max() < 0.005
    again, _ = tr.solve(*walk_problem)          # buffers reused: the same numbers again
    assert np.array_equal(again, out)


@requires_shared
@pytest.mark.parametrize("compiled", [True, False], ids=["C loop", "Python loop"])
def test_leg_tracker_generic_paths_give_the_fast_paths_numbers(op3, walk_problem, compiled, monkeypatch):
    """Leg hinges addressed by an index array (as for a model whose leg joints are not consecutive
    in qpos) and the limit depth from the two one-sided terms (as for hinges narrower than two
    LIMIT_ZONEs): bit for bit the same trajectory as the slice/clip paths op3 takes."""
    if not compiled:
        monkeypatch.setattr(tracker_kernel, "library", lambda: None)
    elif tracker_kernel.library() is None:
        pytest.skip("no C compiler: the tracker runs its Python loop")
    fast = LegTracker(op3)
    assert isinstance(fast._legq, slice) and fast._zones_apart
    generic = LegTracker(op3)
    generic._legq, generic._qpos_legs, generic._zones_apart = generic.qadr, None, False
    a, ea = fast.solve(*walk_problem)
    b, eb = generic.solve(*walk_problem)
    assert np.array_equal(a, b) and np.array_equal(ea, eb)


@requires_shared
def test_the_compiled_frame_loop_gives_the_python_loops_numbers(op3, walk_problem, monkeypatch):
    """The C frame loop (:mod:`~motion2robot.retarget.tracker_kernel`) against the Python one, from
    the previous frames and from a start trajectory (a later round's): bit for bit."""
    if tracker_kernel.library() is None:
        pytest.skip("no C compiler: the tracker runs its Python loop")
    Q, corners, com_xy, fps = walk_problem[:4]
    compiled = LegTracker(op3).solve(Q, corners, com_xy, fps)
    shifted = com_xy + 0.003  # a second round: the CoM path moved, each frame from the first round's
    compiled_again = LegTracker(op3).solve(Q, corners, shifted, fps, compiled[0])
    monkeypatch.setattr(tracker_kernel, "library", lambda: None)
    python = LegTracker(op3).solve(Q, corners, com_xy, fps)
    python_again = LegTracker(op3).solve(Q, corners, shifted, fps, python[0])
    for a, b in zip(compiled + compiled_again, python + python_again):
        assert np.array_equal(a, b)
    assert not np.array_equal(compiled[0], compiled_again[0])  # the second round did move

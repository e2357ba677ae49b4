"""Executable by construction: the tempo/legs policy on real clips, the ZMP planning stage, the
configuration smoothing, planted soles that neither slide nor twist, and the CLI's answers."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.cli import main
from motion2robot.motion import read_motion
from motion2robot.motion.ops import trim
from motion2robot.retarget import RetargetOptions, retarget, retarget_and_check, whole_body
from motion2robot.retarget.smoothing import smooth_jointly
from motion2robot.retarget.zmp_plan import GRAVITY, MIN_SHIFT, cart_table_shift
from motion2robot.robot import load_robot
from motion2robot.validate import check
from tests._shared import MOTIONS, requires_shared


@pytest.fixture(scope="module")
def op3():
    return load_robot("op3")


def _box(T, half=0.03):
    planes = np.tile([0.0, 0.0, 1.0], (T, 8, 1))
    planes[:, :4] = [(1, 0, half), (-1, 0, half), (0, 1, half), (0, -1, half)]
    return planes


def test_cart_table_shift_puts_the_zmp_inside_and_starts_and_ends_at_rest():
    T, fps, z = 200, 50.0, 0.25
    t = np.arange(T) / fps
    zmp = np.stack([0.06 * np.exp(-((t - 2.0) / 0.3) ** 2), np.zeros(T)], axis=1)  # 6 cm out, then back
    d, outside = cart_table_shift(zmp, np.full(T, z), _box(T), np.ones(T, bool), fps)
    dd = np.zeros_like(d)
    dd[1:-1] = (d[2:] - 2 * d[1:-1] + d[:-2]) * fps ** 2
    corrected = zmp + d - z / GRAVITY * dd
    assert np.abs(corrected[:, 0]).max() <= 0.03 + 1e-4
    assert outside.max() < 1e-4
    assert np.abs(d[:3]).max() < 1e-3 and np.abs(d[-3:]).max() < 1e-3  # at rest at both ends
    assert np.abs(np.diff(d, 2, axis=0)).max() * fps ** 2 < 5.0  # smooth, no kink


def test_a_zmp_already_inside_needs_no_shift_and_is_told_apart_from_one_outside():
    """A ZMP inside every supported frame's box gets no shift at all from ``cart_table_shift``
    (exact zeros: the QP is not solved), one 5 mm out of it for 0.4 s is shifted; unsupported
    frames, frames without a ZMP and padding planes do not count."""
    T, fps, z = 200, 50.0, 0.25
    t = np.arange(T) / fps
    zmp = np.stack([0.025 * np.sin(t), np.zeros(T)], axis=1)
    support = np.ones(T, bool)

    def shift(p: np.ndarray, supported: np.ndarray) -> np.ndarray:
        d, slack = cart_table_shift(p, np.full(T, z), _box(T), supported, fps)
        assert not slack.any()
        return d

    assert not shift(zmp, support).any()
    out = zmp.copy()
    out[110:130, 1] = 0.035
    assert np.abs(shift(out, support)).max() > MIN_SHIFT
    free = support.copy()
    free[110:130] = False
    nan = out.copy()
    nan[110:130] = np.nan
    assert not shift(out, free).any() and not shift(nan, support).any()


def test_smooth_jointly_filters_every_column_alike():
    rng = np.random.default_rng(1)
    T = 120
    a = np.cumsum(rng.normal(0, 0.01, T))
    a[60] += 0.05  # a single-frame kink
    b = np.sin(np.arange(T) / 10)
    x = np.stack([a, b, 2 * a - 3 * b], axis=1)  # a point pinned by a linear "kinematics"
    y = smooth_jointly(x, np.full(3, np.inf), np.full(3, 2.0), 20.0)
    np.testing.assert_allclose(y[:, 2], 2 * y[:, 0] - 3 * y[:, 1], atol=1e-12)
    assert np.abs(np.diff(y[:, 0], 2)).max() < np.abs(np.diff(a, 2)).max() / 3


@requires_shared
def test_a_walk_becomes_feasible_under_auto_and_says_how(op3):
    human = read_motion(MOTIONS / "bvh" / "bandai_walk_normal_001.bvh")[0]
    human = trim(human, 0, 90)
    motion, report = retarget_and_check(human, op3)
    assert report is not None and report.feasible, report.reasons
    assert motion.meta["executable"] is True
    assert motion.meta["tempo_reason"]
    # whatever it took is in the meta: the attempts, the tempo, the alternative and why
    assert motion.meta["attempts"][0] == {"legs": "whole", "tempo": 1.0, "feasible": False,
                                          "failed": motion.meta["attempts"][0]["failed"]} or motion.meta["fallback"] is None
    # the robot walks it: the human's footsteps as a walking pattern, not a stance
    fb = motion.meta["fallback"]
    assert fb["mode"] == "steps" and "whole fails" in fb["why"] and "shortened to" in fb["what"], fb
    walk = motion.meta["solver"]["steps"]
    assert 0.05 < walk["step_factor"] < 1.0 and walk["path_m"] > 0.1
    assert report.figures["tempo"] == motion.meta["tempo"]
    assert check(motion, op3).feasible  # the saved motion passes on its own


@requires_shared
def test_a_run_is_walked_with_a_foot_always_down_and_says_why(op3):
    human = read_motion(MOTIONS / "bvh" / "bandai_run_normal_001.bvh")[0]
    motion = retarget(human, op3)
    fb = motion.meta["fallback"]
    assert fb["mode"] == "steps" and "flight" in fb["why"] and "a foot always on the floor" in fb["why"]
    assert "whole" not in [a["legs"] for a in motion.meta["attempts"]]  # flight: the whole body is not tried
    assert motion.meta["executable"] is True
    planted = np.asarray(motion.meta["contacts"], bool)
    assert planted.any(axis=1).all()  # never both feet in the air


@requires_shared
def test_quasi_static_clips_keep_their_tempo(op3):
    for rel in ("bvh/bandai_byebye_normal_001.bvh", "humanml3d_joints/M010968.npy"):
        motion = retarget(read_motion(MOTIONS / rel)[0], op3)
        assert motion.meta["tempo"] == 1.0 and motion.meta["fallback"] is None, (rel, motion.meta["attempts"])
        assert motion.meta["executable"] is True


@requires_shared
def test_planted_soles_neither_slide_nor_twist(op3):
    """A walk in a circle, whole body at the human's tempo: every corner of a planted sole stays
    within 1 cm/s (the sole centre alone was pinned before, and soles twisted while the body turned)."""
    human = trim(read_motion(MOTIONS / "humanml3d_joints" / "000021_raw_joints52.npy")[0], 0, 100)
    motion = whole_body(human, op3)
    from motion2robot.retarget.compiled import compiled_problem

    T = motion.num_frames
    _, corners, _, _ = compiled_problem(op3).points_eval(T)(motion.qpos)
    corners = corners.reshape(T, 2, 4, 3)
    planted = np.asarray(motion.meta["contacts"], bool)
    both = planted[1:] & planted[:-1]
    speed = np.linalg.norm(np.diff(corners[..., :2], axis=0), axis=-1).max(axis=-1) * motion.fps  # (T-1, 2)
    assert both.sum() > 40
    assert speed[both].max() < 0.01


@requires_shared
def test_finer_output_rate_reveals_no_spike(op3):
    """The same clip at 100 fps: peak root and joint accelerations within 1.5x of the native rate's."""
    human = read_motion(MOTIONS / "bvh" / "bandai_byebye_normal_001.bvh")[0]
    opts = RetargetOptions(tempo="human", legs="whole")
    native = retarget(human, op3, opts)
    fine = retarget(human, op3, RetargetOptions(tempo="human", legs="whole", fps=100.0))

    def peaks(m):
        acc = np.diff(m.qpos, 2, axis=0) * m.fps ** 2
        return np.abs(acc[:, :3]).max(), np.abs(acc[:, 7:]).max()

    (rn, jn), (rf, jf) = peaks(native), peaks(fine)
    assert rf <= 1.5 * rn and jf <= 1.5 * jn, (rn, rf, jn, jf)


@requires_shared
@pytest.mark.parametrize("rel, clip, legs", [
    ("mdm_results/mdm_throw_ball_results.npy", 1, "whole"),    # an elbow grazing the hip: the last
    # projection pushed the legs out of it in single frames (553 rad/s^2 in a hip, 23 m/s^2 root)
    ("mdm_results/mdm_throw_ball_results.npy", 5, "stance"),   # a shoulder at its limit: the low-pass
    # rounded it past the limit and the clip left a kink (24 -> 44 rad/s^2)
    ("bvh/bandai_bow_normal_001.bvh", 0, "whole"),             # the solve's last frames ran ahead of
    # the rest (root 0.2 -> 0.4 m/s^2)
])
def test_100_fps_has_no_spike_the_native_rate_hides(op3, rel, clip, legs):
    """Issue 16's artefact line on clips that failed it: at 100 fps the peak root and joint
    accelerations stay within 1.5x of the native rate's, and the finer motion keeps its soles and
    stays out of self-collision."""
    from motion2robot.validate import CheckOptions

    human = read_motion(MOTIONS / rel, clip=clip)[0]
    native = retarget(human, op3, RetargetOptions(tempo="human", legs=legs))
    fine = retarget(human, op3, RetargetOptions(tempo="human", legs=legs, fps=100.0))

    def peaks(m):
        acc = np.diff(m.qpos, 2, axis=0) * m.fps ** 2
        return np.abs(acc[:, :3]).max(), np.abs(acc[:, 7:]).max()

    (rn, jn), (rf, jf) = peaks(native), peaks(fine)
    assert rf <= 1.5 * rn and jf <= 1.5 * jn, (rn, rf, jn, jf)
    report = check(fine, op3, CheckOptions(physics=False))
    assert report.checks["ground"]["ok"] and report.checks["self_collision"]["ok"], report.reasons


@requires_shared
def test_cli_tempo_answers(tmp_path, capsys):
    src = MOTIONS / "humanml3d_joints" / "M010968.npy"
    for bad in (["--tempo", "0"], ["--tempo", "fast"], ["--tempo-cap", "nan"], ["--legs", "none"]):
        with pytest.raises(SystemExit) as exc:  # argparse: usage and the one error line, exit 2
            main(["retarget", str(src), *bad, "-o", str(tmp_path / "a.npz")])
        assert exc.value.code == 2
        assert bad[0] in capsys.readouterr().err
    assert not (tmp_path / "a.npz").exists()
    assert main(["retarget", str(src), "-o", str(tmp_path / "b.npz")]) == 0
    out = capsys.readouterr().out
    assert "tempo x1.00" in out
    # a cap that cannot be met: reported, the best attempt written, exit 1, no crash
    dance = MOTIONS / "bvh" / "bandai_kick_normal_001.bvh"
    code = main(["retarget", str(dance), "--legs", "whole", "--tempo-cap", "1", "-o", str(tmp_path / "c.npz")])
    out = capsys.readouterr().out
    assert code == 1 and "not executable" in out and (tmp_path / "c.npz").is_file()


def test_a_clip_that_never_touches_the_floor_is_one_line_and_exit_2(tmp_path, capsys):
    """A motion floating a metre up (no contact frame at all): nothing to stand on, so no tempo or
    stance can help; a one-line error, exit 2, nothing written."""
    from motion2robot.motion.human import SMPL22
    T = 40
    pos = np.zeros((T, len(SMPL22), 3))
    pos[..., 1] = np.linspace(0, 1, len(SMPL22))[None, :]  # a vertical line of joints, y up
    pos[..., 1] += 1.0 + 0.3 * np.sin(np.arange(T) / 5)[:, None]
    pos[:, :, 0] = np.arange(T)[:, None] * 0.05  # and drifting: no foot is ever still
    src = tmp_path / "floating.npy"
    np.save(src, pos.astype(np.float32))
    code = main(["retarget", str(src), "--format", "humanml3d_joints", "-o", str(tmp_path / "f.npz")])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "floor" in err
    assert not (tmp_path / "f.npz").exists()


def test_auto_legs_order_follows_the_clip():
    """Whole body first; a travelling clip tries steps before the stance, one in place the stance
    first; no steps without a step; flight skips the whole body."""
    from motion2robot.motion.human import HumanMotion
    from motion2robot.retarget.executable import auto_legs

    T = 40
    pos = np.zeros((T, 22, 3))
    walk = HumanMotion(pos + np.linspace(0, 1.0, T)[:, None, None] * [1.0, 0.0, 0.0], 20.0)   # pelvis goes 1 m
    still = HumanMotion(pos.copy(), 20.0)
    stepping = np.zeros((T, 2), bool)
    stepping[:10, 0] = stepping[20:, 0] = True
    stepping[:, 1] = True
    standing = np.ones((T, 2), bool)
    assert auto_legs(walk, stepping, False) == ["whole", "steps", "stance"]
    assert auto_legs(still, stepping, False) == ["whole", "stance", "steps"]
    assert auto_legs(walk, standing, False) == ["whole", "stance"]
    assert auto_legs(walk, stepping, True) == ["steps", "stance"]


@requires_shared
def test_a_gliding_thrower_tries_its_steps_then_the_stance_before_slowing(op3):
    """MDM's throw #5 glides 5 m (its pelvis travels), but its steps keep 4 % of their length
    (told by the steps' first stage): a glide. At the first tempo its steps go first, as for any
    clip that travels (on the gliding throws they were 1.6-3.8 cm nearer than the stance), pass
    and are kept, the glide noted; throw #22 travels and steps (not a glide) and is slowed, then replayed at x1.0,
    which passes."""
    from motion2robot.retarget.executable import GLIDE_SHARE

    clips = MOTIONS / "mdm_results" / "mdm_throw_ball_results.npy"
    motion = retarget(read_motion(clips, clip=5)[0], op3)
    assert motion.meta["fallback"]["mode"] == "steps" and motion.meta["tempo"] == 1.0
    assert [(a["legs"], a["tempo"], a["feasible"]) for a in motion.meta["attempts"]] == [("steps", 1.0, True)]
    assert [s["legs"] for s in motion.meta["legs_skipped"] if s.get("set_aside")] == ["steps"]
    assert motion.meta["solver"]["steps"]["step_factor"] < GLIDE_SHARE and "nearness" not in motion.meta
    slowed = retarget(read_motion(clips, clip=22)[0], op3)
    assert [(a["legs"], a["tempo"]) for a in slowed.meta["attempts"]] == [("steps", 1.0), ("steps", 1.25), ("steps", 1.0)]
    assert slowed.meta["replayed"] == {"from_tempo": 1.25} and slowed.meta["tempo"] == 1.0  # replayed at x1.0
    assert slowed.meta["solver"]["steps"]["step_factor"] >= GLIDE_SHARE


def test_a_glide_whose_steps_fail_keeps_the_tempo_in_the_stance(monkeypatch):
    """The order of a glide's attempts: the steps, then the stance, at the first tempo, before
    either slower (stand-ins for the solve and the judge: the steps pass only slowed, the stance
    at x1; the whole body set aside)."""
    import motion2robot.retarget.executable as ex
    from motion2robot.motion import HumanMotion

    T = 40
    pos = np.zeros((T, 22, 3))
    pos[:, :, 2] = 0.9
    labels = np.ones((T, 2), bool)
    labels[10:15, 0] = labels[25:30, 0] = labels[18:22, 1] = False  # the left foot steps twice
    human = HumanMotion(pos + np.linspace(0, 2.0, T)[:, None, None] * [1.0, 0.0, 0.0], 20.0,
                        contacts=labels)  # the pelvis goes 2 m
    made = []

    class Report:
        def __init__(self, ok):
            self.feasible, self.figures = ok, {}
            self.checks = {} if ok else {"balance": {"ok": False}}

    class Motion:
        def __init__(self, legs, k):
            self.legs, self.k, self.meta = legs, k, {}

        def with_(self, meta):
            self.meta = {**self.meta, **meta}
            return self

    def solve(h, legs):
        made.append((legs, round(h.num_frames / T, 2)))
        return Motion(*made[-1])

    monkeypatch.setattr(ex, "short_shifts", lambda *a: "set aside for the test")
    monkeypatch.setattr(ex, "_judge", lambda robot, options, full=False: lambda m: Report(m.legs == "stance" or m.k > 1))
    motion, _ = ex.plan(human, None, "auto", "auto", 2.5, solve, probe=lambda h: 0.04)
    assert made == [("steps", 1.0), ("stance", 1.0)] and (motion.legs, motion.k) == ("stance", 1.0)


@requires_shared
def test_a_clip_in_place_is_walked_when_its_steps_are_nearer_than_the_stance(op3):
    """HumanML3D 011673 sits down on the floor: its pelvis stays within 0.5 m, so the stance goes
    first for its tempo. The stance (after its solves) and the steps of x1 are measured against
    the same scaled human (``score``'s keypoint error): the steps are nearer, judged first, pass
    and are kept, the stance never judged, and the fallback says so."""
    from motion2robot.retarget.nearness import keypoint_error
    from motion2robot.score.fidelity import fidelity

    human = read_motion(MOTIONS / "humanml3d_joints" / "011673.npy")[0]
    motion = retarget(human, op3)
    assert motion.meta["fallback"]["mode"] == "steps" and motion.meta["tempo"] == 1.0
    assert [a["legs"] for a in motion.meta["attempts"]] == ["whole", "whole", "steps"]
    near = motion.meta["nearness"]
    assert near["kept"] == "steps" and near["keypoint_error_m"]["steps"] < near["keypoint_error_m"]["stance"]
    assert "the steps at x1.00 are nearer to the human than the stance" in motion.meta["fallback"]["why"]
    # the figures compared are score's fidelity figure: of the steps returned, and of the stance
    # after its solves (its later stages move it a few mm, away from the human)
    assert abs(near["keypoint_error_m"]["steps"] - keypoint_error(motion, human, op3)) < 1e-5
    assert abs(near["keypoint_error_m"]["steps"] - fidelity(human, motion, op3)["keypoint_error_m"]) < 1e-4
    stood = retarget(human, op3, RetargetOptions(tempo=1.0, legs="stance"))
    assert near["stance_measured"] == "solves" and "after its solves" in motion.meta["fallback"]["why"]
    assert abs(near["keypoint_error_m"]["stance"] - keypoint_error(stood, human, op3)) < 0.005


@requires_shared
def test_the_stance_is_kept_when_the_steps_are_farther(op3):
    """Bandai's punch stays in place and shuffles its feet: the stance and the steps of the first
    tempo are made, the steps measured farther from the human, so the stance is judged, passes
    and is kept, the steps never judged, and the fallback says so."""
    human = read_motion(MOTIONS / "bvh" / "bandai_punch_normal_001.bvh")[0]
    motion = retarget(human, op3)
    assert motion.meta["fallback"]["mode"] == "stance" and motion.meta["tempo"] == 1.0
    # the stance kept went on from the solves the comparison measured: the stance, to the bit
    assert np.array_equal(motion.qpos, retarget(human, op3, RetargetOptions(tempo=1.0, legs="stance")).qpos)
    assert [a["legs"] for a in motion.meta["attempts"]] == ["stance"]
    near = motion.meta["nearness"]
    assert near["kept"] == "stance" and near["keypoint_error_m"]["steps"] > near["keypoint_error_m"]["stance"]
    assert "steps at x1.00 are farther from the human" in motion.meta["fallback"]["why"]


def test_ascending_search_stops_at_the_first_tempo_that_passes():
    from motion2robot.retarget.executable import Attempt, _search

    class Report:
        def __init__(self, ok, failed=()):
            self.feasible, self.checks = ok, {n: {"ok": False} for n in failed}

    class Motion:
        meta: dict = {}

    made = []

    def make(k, passes_from=1.6):
        made.append(k)
        ok = k >= passes_from
        return Attempt("steps", k, Motion(), Report(ok, () if ok else ("torque_limits",)))

    ok, tried = _search(make, [1.0, 1.25, 1.6, 2.0, 2.5], ascending=True)
    assert ok.factor == 1.6 and made == [1.0, 1.25, 1.6]
    made.clear()
    ok, tried = _search(make, [1.0, 1.25, 1.6, 2.0, 2.5])   # the default: the cap, then between
    assert ok.factor == 1.6 and made == [1.0, 2.5, 1.25, 1.6]
    made.clear()
    ok, _ = _search(lambda k: make(k, passes_from=9.0), [1.0, 1.25, 2.5], ascending=True)
    assert ok is None and made == [1.0, 1.25, 2.5]
    made.clear()

    def worsening(k):  # slower, a check the faster one passed fails too: not the tempo's doing
        made.append(k)
        return Attempt("steps", k, Motion(), Report(False, ("torque_limits",) + (("balance",) if k > 1.2 else ())))

    ok, _ = _search(worsening, [1.0, 1.25, 1.6, 2.0, 2.5], ascending=True)
    assert ok is None and made == [1.0, 1.25]

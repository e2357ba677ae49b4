"""Footholds for a walking pattern: the human's placements re-laid within the robot's reach.

:func:`feet_placements` reads where the human's feet stand and point in each contact phase. A
human stride scaled to a small robot is still too long for it (op3: the Bandai walk asks for 0.22
m between the feet, 80 % of its straight leg), and a human sets its feet closer together than the
robot's hips. :func:`shorten_steps` re-lays the placements step by step: each step keeps the
human's turn and sideways offset, its fore-aft length shrinks by the clip's :func:`step_factor`,
and a foot set beside the other stays :func:`stance_width` to its side (a wider human step's excess
shrinks by the same factor). A foot that steps twice in a row is laid from the foot it stands
beside. Every placement keeps its yaw within the hips' reach. :func:`grounded` gives every
lift-off a double support before it (the human's flight phases and heel-up frames leave none);
:func:`walking_labels` schedules the steps to their fixed point; :func:`filled` gives a foot in the
air at either end of the clip its nearest placement. Units: metres, radians, seconds; world frame
z up.
"""

from __future__ import annotations

import numpy as np

from motion2robot.errors import SolverError
from motion2robot.retarget.contact_plan import ContactPlan
from motion2robot.retarget.contacts import phases, sole_yaw, yaw_rotation
from motion2robot.robot.chains import hip_hinges
from motion2robot.robot.robot import Robot


#: Rounds of (widen, ground) :func:`walking_labels` runs at most to reach its fixed point.
SCHEDULE_ROUNDS = 12


class PatternError(SolverError):
    """The clip gives no walking pattern (a foot never stands on the floor): ``steps`` cannot be
    tried on it (``auto`` goes on to the next alternative; ``--legs steps`` reports it)."""


def _sole_yaw(corners: np.ndarray) -> float:
    """Yaw (rad) of one sole from its (4, 3) corners (:func:`~.contacts.sole_yaw`)."""
    return float(sole_yaw(corners))


def _steps(labels: np.ndarray) -> list[tuple[int, int, int, tuple[int, int, int] | None]]:
    """The contact phases in order of their first frame as (foot, first, end, reference): the
    reference is the phase the robot stands on as the foot lands, i.e. the other foot's latest
    phase if that foot is down in the frame before (a foot stepping twice in a row is laid from
    the other foot, not from its own last placement: its shuffles must not drift away from the
    foot it stands beside), else the phase before it; None for the phases the clip starts with."""
    runs = sorted(phases(labels), key=lambda r: (r[1], r[0]))
    out = []
    for i, (f, a, b) in enumerate(runs):
        before = [r for r in runs[:i] if r[1] < a]
        stood = [r for r in before if r[0] != f and r[2] >= a]
        ref = stood[-1] if stood else (before[-1] if before else None)
        out.append((f, a, b, ref))
    return out


def _axes(yaw: float) -> tuple[np.ndarray, np.ndarray]:
    return np.array([np.cos(yaw), np.sin(yaw)]), np.array([-np.sin(yaw), np.cos(yaw)])


def _step_yaw(from_yaw: float, to_yaw: float) -> float:
    """Heading (rad) of a step: midway between the placement it steps from (the foot the robot
    stands on while it swings) and its own. A walk's feet point out to either side of where it
    goes (the CMU walk: the left 0.3 rad, the right 0.0), so a step measured in the standing
    foot's heading alone went sideways by its toe-out and was measured short (the op3 stepped 7
    cm for a 5 cm reach)."""
    return from_yaw + 0.5 * _wrap(to_yaw - from_yaw)


def _step_axes(soles: np.ndarray, ref: tuple[int, int, int], f: int, a: int) -> tuple[np.ndarray, np.ndarray]:
    """Forward and left unit vectors of the step of foot ``f`` landing in frame ``a`` from the
    placement ``ref`` (:func:`_step_yaw`)."""
    return _axes(_step_yaw(_sole_yaw(soles[ref[1], ref[0]]), _sole_yaw(soles[a, f])))


def feet_placements(soles: np.ndarray, labels: np.ndarray, own: np.ndarray, ankles: np.ndarray, toes: np.ndarray,
                    offsets: np.ndarray, turns: np.ndarray) -> np.ndarray:
    """(T, 2, 4, 3) placements in the ``labels`` (T, 2) contact frames from the human's own feet
    (``ankles``, ``toes``: (T, 2, 2) their scaled horizontal positions, m): per contact phase, the
    robot's own ankle->toe keypoints point along the human's ankle->toe direction summed over the
    phase's frames in which the human's foot is down (``own`` (T, 2): its planted frames; the
    phase's first frame if none), i.e. the sole heads ``turns`` (2,) (rad, the robot's
    ankle->toe keypoints' heading in its sole's frame) short of it, and its centre is the ankle
    where the foot lands (the first of those frames: a gliding thrower's foot is laid where it
    lands, as its steps are measured) plus the robot's ankle->sole-centre ``offsets`` (2, 2) (m,
    forward and left in the sole's frame) turned to that heading; the sole's layout is ``soles``' (the
    unpinned solve's placements, :func:`~.contacts.anchor_soles`), at z = 0. A walk's foot that
    stands still gives exactly where it stands."""
    out = soles.copy()
    for f, a, b in phases(labels):
        frames = a + np.flatnonzero(own[a:b, f]) if own[a:b, f].any() else np.array([a])
        fwd = (toes[frames, f] - ankles[frames, f]).sum(axis=0)
        yaw = float(np.arctan2(fwd[1], fwd[0])) - float(turns[f])
        centre = ankles[frames[0], f] + yaw_rotation(yaw) @ offsets[f]
        out[a:b, f] = _turned(soles[a, f], centre, yaw)
        out[a:b, f, :, 2] = 0.0
    return out


def _start(soles: np.ndarray, runs: list) -> tuple[float, float, float] | None:
    """The stance the clip starts on, when both feet start on the floor: their mean heading (rad),
    and the left sole's centre from the right's, forward and leftward in that heading (m)."""
    first = {f: a for f, a, _, ref in runs if ref is None}
    if len(first) != 2:
        return None
    ya, yb = (_sole_yaw(soles[first[f], f]) for f in (0, 1))
    mean = ya + 0.5 * _wrap(yb - ya)
    gap = soles[first[0], 0].mean(axis=0)[:2] - soles[first[1], 1].mean(axis=0)[:2]
    fwd, left = _axes(mean)
    return mean, float(gap @ fwd), float(gap @ left)


def step_factor(soles: np.ndarray, labels: np.ndarray, longest: float, slack: float = 0.0) -> float:
    """The factor (<= 1) that brings the longest step down to ``longest`` (m): a step's length is
    the fore-aft distance, in its heading (:func:`_step_axes`), from the placement before it to
    its own (``soles`` (T, 2, 4, 3) placements in the ``labels`` (T, 2) contact frames); the
    stance the clip starts on counts as one (a clip cut mid-stride starts with its feet a stride
    apart). Steps up to ``slack`` (a fraction) longer than ``longest`` are kept as they are
    (1.0): a walking pattern's own placements, where the feet were pushed apart so as not to
    meet, measure a little over the reach it laid them at."""
    runs = _steps(labels)
    start = _start(soles, runs)
    worst = 0.0 if start is None else abs(start[1])
    for f, a, _, ref in runs:
        if ref is None:
            continue
        fwd, _ = _step_axes(soles, ref, f, a)
        gap = soles[a, f].mean(axis=0)[:2] - soles[ref[1], ref[0]].mean(axis=0)[:2]
        worst = max(worst, abs(float(gap @ fwd)))
    if worst <= longest * (1.0 + slack):
        return 1.0
    return float(longest / max(worst, 1e-9))


def _wrap(a: float) -> float:
    return float((a + np.pi) % (2 * np.pi) - np.pi)


def _turned(sole: np.ndarray, centre: np.ndarray, yaw: float) -> np.ndarray:
    """(4, 3) the sole ``sole`` (4, 3) turned about its centre to ``yaw`` and moved to ``centre`` (2,)."""
    c0 = sole.mean(axis=0)
    out = sole.copy()
    out[:, :2] = (sole[:, :2] - c0[:2]) @ yaw_rotation(yaw - _sole_yaw(sole)).T + centre
    return out


def shorten_steps(soles: np.ndarray, labels: np.ndarray, k: float, width: float, max_turn: float,
                  turn_rate: float = np.inf) -> np.ndarray:
    """Placements re-laid step by step (:func:`_steps`), each from the re-laid placement it steps
    from: the step keeps the human's turn and, in its heading (:func:`_step_yaw`), its sideways
    offset, while its fore-aft length shrinks
    by ``k``, a foot set beside the other lands at least ``width`` (m) to its own side of it (the
    robot's own stance width: its hip rolls cannot hold the body over a foot set inside the hip,
    as a human's narrower placements would ask) and what the human's step reaches sideways beyond
    that shrinks by ``k`` too (op3: a thrower's side step of 0.19 m between the feet held the swing
    ankle's roll at its limit, a kink of 400-800 rad/s^2 at 100 fps), and a foot turns at
    most ``max_turn`` (rad) from the one it steps from (the hip yaws' range; the human's heading
    is caught up on the next steps). The feet the clip starts on (both down in its first phase)
    stand about their midpoint as one such step apart, in their mean heading and turned to within
    ``max_turn / 2`` of it (a clip cut mid-stride, laid as the human stood, started the op3 a
    human stride apart: 18 cm, its knee at 5x its torque); a foot turns from its own last
    placement by at most ``turn_rate`` (rad per frame of its swing: what its hip yaw can turn it
    by in the air).
    ``soles``: (T, 2, 4, 3) placements in the ``labels`` (T, 2) contact frames."""
    out = soles.copy()
    runs = _steps(labels)
    start = _start(soles, runs)
    if start is not None:  # the feet the clip starts on: a stance of the robot's, about their midpoint
        mean, fore, lat = start
        fwd, left = _axes(mean)
        half = 0.5 * (k * fore * fwd + (width + k * max(lat - width, 0.0)) * left)
        first = [(f, a, b) for f, a, b, ref in runs if ref is None]
        mid = 0.5 * sum(soles[a, f].mean(axis=0)[:2] for f, a, _ in first)
        for f, a, b in first:
            yaw = mean + float(np.clip(_wrap(_sole_yaw(soles[a, f]) - mean), -max_turn / 2, max_turn / 2))
            out[a:b, f] = _turned(soles[a, f], mid + (half if f == 0 else -half), yaw)
    for f, a, b, ref in runs:
        if ref is None:
            continue
        fwd, left = _step_axes(soles, ref, f, a)               # the human's step, in its frame
        gap = soles[a, f].mean(axis=0)[:2] - soles[ref[1], ref[0]].mean(axis=0)[:2]
        fore, lat = float(gap @ fwd), float(gap @ left)
        if ref[0] != f:
            side = 1.0 if f == 0 else -1.0
            lat = side * (width + k * max(side * lat - width, 0.0))
        else:
            lat *= k
        base = out[ref[1], ref[0]]
        yaw_ref = _sole_yaw(base)
        yaw = yaw_ref + float(np.clip(_wrap(_sole_yaw(soles[a, f]) - yaw_ref), -max_turn, max_turn))
        own = np.flatnonzero(labels[:a, f])
        if len(own) and np.isfinite(turn_rate):  # the turn its swing has time for
            last = _sole_yaw(out[own[-1], f])
            room = turn_rate * (a - 1 - own[-1])
            yaw = last + float(np.clip(_wrap(yaw - last), -room, room))
        fwd, left = _axes(_step_yaw(yaw_ref, yaw))             # laid from the re-laid placement
        out[a:b, f] = _turned(soles[a, f], base.mean(axis=0)[:2] + k * fore * fwd + lat * left, yaw)
    return out


def stance_width(robot: Robot) -> float:
    """m between the sole centres of a walking stance: the legs straight down from the hips (the
    distance between the first hinges of the two legs at the nominal posture), or the soles' width
    and a centimetre if that is more (the soles must not meet)."""
    d = robot.new_data()
    hips = [d.xanchor[robot.joint_ids[j]] for j in hip_hinges(robot)]
    soles = 2.0 * max(f.sole_half[1] for f in robot.config.feet) + 0.01
    return float(max(np.linalg.norm(hips[0][:2] - hips[1][:2]), soles))


def widen_swings(labels: np.ndarray, min_frames: int, keep: int = 1) -> np.ndarray:
    """(T, 2) contact labels in which every swing (a foot in the air between two of its contact
    phases) lasts at least ``min_frames``: a shorter one lifts off earlier and sets down later by
    about the same number of frames, taken from the foot's own contact phases where the other
    foot is down (it carries the body meanwhile) and leaving each phase at least ``keep`` frames
    (a phase already that short gives nothing); a swing with no room keeps what it can get."""
    out = labels.copy()
    T = len(out)
    for f in range(out.shape[1]):
        other = out[:, 1 - f]
        for _, a, b in sorted(phases(~out[:, f:f + 1]), key=lambda r: r[1]):
            if a == 0 or b >= T or b - a >= min_frames:
                continue
            before = 0  # frames of this foot's phase before the swing that can join it
            while a - before - 1 - keep >= 0 and out[a - before - 1 - keep:a - before - 1, f].all() and other[a - before - 1]:
                before += 1
            after = 0
            while b + after + keep < T and out[b + after + 1:b + after + 1 + keep, f].all() and other[b + after]:
                after += 1
            need = min_frames - (b - a)
            late = min(after, need - min(before, need // 2))
            early = min(before, need - late)
            out[a - early:a, f] = False
            out[b:b + late, f] = False
    return out


def grounded(labels: np.ndarray, fps: float, overlap_s: float, min_swing_s: float,
             keep_swing_s: float = 0.0) -> np.ndarray:
    """(T, 2) contact labels in which a foot lifts off only after the other has been down for
    ``overlap_s``: a phase whose foot would lift with the other foot in the air (a run's flight, a
    jump) or just landed (a human walk's heel-up frames leave no double support) is extended until
    the other foot has landed and ``overlap_s`` more, as long as ``min_swing_s`` of its next swing
    is left (the ZMP then moves across a double support instead of jumping between the soles);
    where that leaves no room before the other foot lands (a hop, a jump with both feet), the
    foot stays down through to its next contact (the hop is dropped). With ``keep_swing_s``, the
    wait stops where it would cut the next swing below ``keep_swing_s`` (or below its own length,
    if shorter): the double support gets shorter instead, down to a frame after the landing."""
    out = labels.copy()
    T = len(out)
    overlap, min_swing = max(1, int(round(overlap_s * fps))), max(1, int(round(min_swing_s * fps)))
    keep_swing = int(round(keep_swing_s * fps))
    for g, a, e in sorted(phases(labels), key=lambda r: r[2]):
        if e >= T:
            continue
        nxt = np.flatnonzero(out[e:, g])
        cap = e + int(nxt[0]) - min_swing if len(nxt) else T  # the next swing keeps min_swing
        other = out[:, 1 - g]
        if other[e - 1] and other[e]:  # the other foot stays down: since when
            up = np.flatnonzero(~other[:e])
            landing = int(up[-1]) + 1 if len(up) else 0
        else:             # it is in the air, or lifts with this one (a jump): when it lands
            down = np.flatnonzero(other[e:])
            if not len(down):
                continue
            landing = e + int(down[0])
        stop = min(landing + overlap, cap)
        if len(nxt) and keep_swing > min_swing and stop > landing:  # the double support gives way
            swing = int(nxt[0])
            keep_cap = e + swing - max(min_swing, min(keep_swing, swing))
            stop = max(landing + 1, min(stop, keep_cap))
        if stop <= landing and len(nxt):  # no room to wait for the other foot (a hop): no swing
            stop = e + int(nxt[0])
        if stop > e:
            out[e:stop, g] = True
    return out


def walking_labels(labels: np.ndarray, fps: float, overlap_s: float, min_swing_s: float,
                   long_swing_s: float = 0.0) -> np.ndarray:
    """(T, 2) contact labels of a walking pattern from the human's (at ``fps``): every swing
    widened to ``min_swing_s`` (:func:`widen_swings`), then to ``long_swing_s`` where the foot's
    contact phases around it keep ``overlap_s`` (quick footwork keeps its short stances), every
    lift-off after a double support of ``overlap_s`` (:func:`grounded`), then all again until
    nothing changes (at most SCHEDULE_ROUNDS times): a swing beside a flight phase has no room
    (the other foot is in the air) until the flight is grounded (a GMD clip at 100 fps kept a
    0.05 s swing there: 600 rad/s^2 in a knee), and widening it can take the double support before
    the other foot's lift-off, which the next grounding gives back. Run to its fixed point, the
    schedule is its own schedule (two rounds left 12 of the 62 dev clips' schedules changing again
    by 1-11 frames, so a motion walked on them was scheduled anew)."""
    n_swing = int(np.ceil(min_swing_s * fps - 1e-9))
    n_long = int(np.ceil(long_swing_s * fps - 1e-9))
    keep = max(1, int(round(overlap_s * fps)))
    out = labels
    for _ in range(SCHEDULE_ROUNDS):
        before = out
        out = widen_swings(out, n_swing)
        if n_long > n_swing:
            out = widen_swings(out, n_long, keep)
        out = grounded(out, fps, overlap_s, min_swing_s, long_swing_s)
        if np.array_equal(out, before):
            break
    return out


def filled(plan: ContactPlan, where: str) -> tuple[np.ndarray, np.ndarray]:
    """(T, 2, 4, 3) corner targets in every frame and (T, 2) support labels: a foot in the air
    before its first contact phase (the human mid-stride at the cut) or after its last stands at
    that phase's placement, so the pattern starts and ends standing."""
    targets, contact = plan.targets.copy(), plan.labels.copy()
    for f in range(2):
        has = np.flatnonzero(~np.isnan(targets[:, f, 0, 0]))
        if not len(has):
            raise PatternError(f"{where}: the {('left', 'right')[f]} foot never stands on the floor, so there are no "
                              "footsteps to walk (--legs steps); use --legs whole or stance")
        a, b = int(has[0]), int(has[-1])
        targets[:a, f], contact[:a, f] = targets[a, f], True
        targets[b + 1:, f], contact[b + 1:, f] = targets[b, f], True
        if np.isnan(targets[:, f, 0, 0]).any():  # every swing is planned (no speed cap): cannot happen
            raise PatternError(f"{where}: a swing of the {('left', 'right')[f]} foot has no plan")
    return targets, contact

"""Executable by choice of tempo and legs: the policy stage around the whole-body retargeter.

``retarget`` with ``tempo="auto"`` and/or ``legs="auto"`` (the defaults) judges what it makes with
the full :func:`~motion2robot.validate.check` (physics playback included) and picks the first
attempt that passes, in this order:

0. a robot-shaped motion (the robot's own motion in the human's space, as ``project`` makes:
   :mod:`~.reach`) its exact poses, as its whole body at x1.0, whatever the legs policy would try
   first for it; failing there on a check a tempo changes, the same poses played slower
   (:func:`~.replay.retimed`), the first of the slower factors that passes;
1. whole body at the generated tempo (x1.0), unless a lift-off of the human's leaves the whole
   body's static balance too little double support to shift its weight even at the slowest
   tempo allowed (:mod:`~.weight_shift`: then it is not tried, and the fallback says why);
2. whole body slowed: first at the cap (if even that fails, no smaller slow-down can pass and the
   steps between are skipped), else the smallest of :data:`~.tempo.AUTO_STEPS` that passes; not
   tried when x1.0 fails a check no tempo changes (:data:`TEMPO_PROOF`: limits, self-collision,
   the feet on the floor, unless the foot plan left swings free as too fast for this tempo);
3. the alternatives, each at x1.0, then slowed (the stance as above, ``steps`` one factor at a
   time, stopping at the first that passes): ``steps`` (:mod:`~.gait`: the
   human's footsteps walked by a walking pattern, steps shortened to what the robot's legs reach,
   the CoM planned so the ZMP stays in the soles, the upper body and head as retargeted) and
   ``stance`` (:mod:`~.stance`: legs in a fixed stance, upper body and head perform). A clip whose
   pelvis travels (more than TRAVEL_M from where it starts) tries ``steps`` first: walking is the
   nearest thing to it; one that stays in place tries ``stance`` first, which keeps its tempo more
   often; one whose ``steps`` would step in place (the steps kept below :data:`GLIDE_SHARE` of the
   human's: a glide, as generated throwers skate, told by ``steps``' first stage alone) tries the
   steps, then the stance, at the first tempo before either slower. Where the stance
   comes before ``steps``, both are made at the first tempo and the nearer to the human
   (:mod:`~.nearness`: the keypoint error ``score`` reports) is judged first; the steps, when
   nearer and passing, are kept (``meta["nearness"]`` says what was compared). The stance is
   measured after its solves (``retarget`` passes a ``sketch``: stages 1-4 of the whole body, half
   its cost, from which the stance goes on when it is judged; its later stages, which make it
   followable by the servos, moved its keypoint error by up to 5 mm on the dev clips, away from
   the human, so the comparison leans to the stance): the stance goes
   first for its tempo, not for being nearer, and a motion that steps on the spot or a little
   way (as the robot's own version of a walk, :mod:`~motion2robot.projection`) is nearer walked
   than stood. ``steps`` is not tried when no foot steps. Clips with flight phases (runs, jumps) skip
   the whole body: a flat-footed robot of servos cannot make the take-off impulse; ``steps`` walks
   them with a foot always on the floor.

A slowed pass is **replayed** nearer the generated tempo before it is kept (:mod:`~.replay`):
its own keypoints, mapped back into the human's space at the human's tempo (the way back of
:mod:`~motion2robot.projection`), are retargeted in its legs mode at x1.0 and judged; when that
fails, its poses are played at each faster factor in turn (:mod:`~.retime`, nothing solved
again), and the first that passes is chosen instead (``meta["replayed"]`` / ``meta["retimed"]``
say from which tempo). The slow pass did what the human's raw motion could not at x1.0 (its
feet planned, its poses made followable at a pace that allows it); at the human's pace those
poses are often still within the robot's reach (2 of 8 slowed dev clips keep x1.0 this way).
Either way the motion kept is one whose retargeting from ``project``'s ``human'`` is exact (its
poses at x1.0, or its poses played at the tempo chosen: stage 0).

Nothing is silent: the result's meta says the tempo factor (``tempo``, 1.0 = as generated), why
(``tempo_reason``), the alternative taken (``fallback``: None, or {"mode", "why"}) and whether the
chosen attempt passed (``executable``). When no attempt passes, the one failing the fewest checks
(the last tried on a tie) is returned with ``executable`` False and the reason.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from motion2robot.motion.human import HumanMotion
from motion2robot.retarget.attempt import TEMPO_PROOF, Attempt, tempo_proof
from motion2robot.retarget.contacts import contact_labels
from motion2robot.retarget.footholds import PatternError
from motion2robot.retarget.judged import needs_full_check
from motion2robot.retarget.nearness import compare, nearness_words, steps_nearer
from motion2robot.retarget.options import LEG_MODES
from motion2robot.retarget.replay import replayed, retimed
from motion2robot.retarget.stance import has_flight
from motion2robot.retarget.tempo import auto_factors, similar_factor, stretch
from motion2robot.retarget.weight_shift import short_shifts
from motion2robot.robot.robot import Robot
from motion2robot.robot_motion import RobotMotion

#: (human motion at the attempt's tempo, legs mode) -> robot motion.
Solve = Callable[[HumanMotion, str], RobotMotion]
#: Legs modes ``auto`` may try (their order: :func:`auto_legs`).
AUTO_LEGS = LEG_MODES
#: m (human): a pelvis that goes farther than this from where it starts travels (a walk, not a
#: motion in place).
TRAVEL_M = 0.5

#: A ``steps`` attempt whose steps keep less than this share of the human's length (its step
#: factor) steps in place: the human's steps are then over 1.8 leg lengths at the robot's scale,
#: beyond a running stride (the dev clips' walks, runs and dances keep 14-63 %; MDM throwers whose
#: pelvis glides 3-5 m keep 4-8 %): glides, not steps, and the stance at the first tempo is tried
#: before the steps are slowed (the steps at that tempo first: on the 6 gliding MDM throws they
#: were 1.6-3.8 cm nearer to the human than the stance, both leaving the glide).
GLIDE_SHARE = 0.1

_MODE_WORDS = {"whole": "the whole body", "steps": "steps", "stance": "the stance"}

def _judge(robot: Robot, options: object | None, full: bool = False) -> Callable[[RobotMotion], object]:
    """``check`` with ``options`` (default: every check); unless ``full``, the physics playback
    only for a motion that passes the kinematic checks."""
    from motion2robot.validate import CheckOptions, check  # the judge sits above the retargeter

    options = options or CheckOptions()
    return lambda motion: check(motion, robot, options, physics_if_feasible=not full)


def _factors(tempo: str | float, cap: float, human: HumanMotion, robot: Robot) -> list[float]:
    if tempo == "human":
        return [1.0]
    if tempo == "similar":
        from motion2robot.retarget.scale import auto_scale

        return [similar_factor(auto_scale(human, robot).legs)]
    if tempo == "auto":
        return auto_factors(cap)
    return [float(tempo)]


def _search(make: Callable[[float], Attempt], factors: list[float],
            ascending: bool = False) -> tuple[Attempt | None, list[Attempt]]:
    """The first passing attempt in ``factors`` order, trying the first, then the last, then the
    ones between (a slower tempo passing is what makes the ones between worth trying); with
    ``ascending``, the first, then each slower one in turn (cheaper where a small slow-down
    suffices, as for the ``steps`` pattern, whose accelerations fall steadily with the tempo),
    stopping where a slower one fails a check the one before passed: what fails there comes from
    the pattern, not its speed (a CMU playground clip of 2,751 frames went on failing up to x2.5:
    20 CPU seconds where stopping at x1.25 takes 5.5)."""
    tried: list[Attempt] = []
    first = make(factors[0])
    tried.append(first)
    if first.feasible or len(factors) == 1 or set(first.failed()) & tempo_proof(first.motion):
        return (first if first.feasible else None), tried
    if ascending:
        for k in factors[1:]:
            a = make(k)
            worse = set(a.failed()) - set(tried[-1].failed())
            tried.append(a)
            if a.feasible or set(a.failed()) & tempo_proof(a.motion) or worse:
                return (a if a.feasible else None), tried
        return None, tried
    last = make(factors[-1])
    tried.append(last)
    if not last.feasible:
        return None, tried
    for k in factors[1:-1]:
        a = make(k)
        tried.append(a)
        if a.feasible:
            return a, tried
    return last, tried


def _retime_reason(final: Attempt, tried: list[Attempt]) -> str:
    """meta["tempo_reason"] of a chosen retimed attempt (:func:`~.replay.retimed`)."""
    first = next(a for a in tried if a.legs == final.legs)
    at = "played at the generated tempo (x1.00)" if final.factor == 1.0 else f"slowed x{final.factor:.2f}"
    if final.retime_of == 1.0:  # a robot-shaped motion's exact poses, slower
        return (f"{at}: the exact poses of this robot-shaped motion, played x{final.factor:.2f} slower, the smallest "
                f"slow-down tried that passes (at x1.00 {_words(first.failed())} failed)")
    return (f"{at}: the robot's motion slowed x{final.retime_of:.2f} (the smallest slow-down of the human's that passes) "
            f"played at x{final.factor:.2f}, its poses unchanged, passes (the human's at x{first.factor:.2f}: "
            f"{_words(first.failed())} failed)")


def _words(failed: list[str]) -> str:
    return ", ".join(failed) if failed else "nothing"


def auto_legs(human: HumanMotion, labels: np.ndarray, flight: bool) -> list[str]:
    """The legs modes ``auto`` tries on ``human`` (contact ``labels`` (T, 2)), in order (see the
    module text)."""
    from motion2robot.motion.human import KP
    from motion2robot.retarget.contacts import phases

    steps = any(sum(1 for g, _, _ in phases(labels) if g == f) > 1 for f in range(labels.shape[1]))
    pelvis = np.asarray(human.positions)[:, KP["pelvis"], :2]
    travels = bool(np.linalg.norm(pelvis - pelvis[0], axis=1).max() > TRAVEL_M)
    order = ["steps", "stance"] if travels else ["stance", "steps"]
    return [m for m in ([] if flight else ["whole"]) + order if m != "steps" or steps]


def _glides(share: float) -> str | None:
    """Why steps keeping ``share`` of the human's length (the step factor) step in place, or None
    when they keep GLIDE_SHARE or more."""
    if share >= GLIDE_SHARE:
        return None
    return (f"the human's steps would keep {100 * share:.0f} % of their length (the robot stepping in place): "
            "they glide rather than step, so the stance at the first tempo goes before the steps slowed")


def legs_of(motion: RobotMotion) -> str:
    """The legs mode ``motion`` was made with: its ``meta["fallback"]["mode"]``, or "whole" (no
    fallback: the whole body)."""
    fallback = motion.meta.get("fallback")
    return str(fallback["mode"]) if isinstance(fallback, Mapping) and fallback.get("mode") else "whole"


def _fallback(final: Attempt, legs: str, flight: bool, tried: list[Attempt], robot: Robot,
              skipped: list[dict], nearness: dict | None = None) -> dict | None:
    """meta["fallback"] of the returned attempt: None for the whole body, else what was done and why."""
    if final.legs == "whole":
        return None
    if legs == final.legs:
        why = f"asked for (--legs {legs})"
    elif flight:
        why = (f"the human motion has flight phases (both feet off the floor), which {robot.name}'s servos "
               "cannot produce" + ("; its steps are walked with a foot always on the floor" if final.legs == "steps"
                                   else ""))
    else:
        noted = {s["legs"] for s in skipped if not s.get("set_aside")}  # set aside, it may still have failed
        why = "; ".join([f"{_MODE_WORDS[s['legs']]} {'set aside' if s.get('set_aside') else 'not tried'}: {s['skipped']}"
                         for s in skipped if s["legs"] != final.legs]
                        + [f"{mode} fails at every tempo tried up to x{runs[-1].factor:.2f} ({_words(runs[-1].failed())})"
                           for mode in AUTO_LEGS if (runs := [a for a in tried if a.legs == mode])
                           and mode != final.legs and mode not in noted and not any(a.feasible for a in runs)]
                        + nearness_words(nearness, final.legs, final.factor))
    if final.legs == "steps":
        walk = (final.motion.meta.get("solver") or {}).get("steps") or {}
        what = (f"the legs walk the human's footsteps as a walking pattern: steps shortened to "
                f"{100 * walk.get('step_factor', 1.0):.0f} % of the human's (scaled) length, the feet "
                f"{100 * walk.get('stance_width_m', 0.0):.1f} cm apart, the pelvis upright, the CoM planned so the "
                "ZMP stays in the soles; the upper body and head perform")
    else:
        what = ("the legs keep a fixed double-support stance at the clip's first heading; "
                "the upper body and head perform")
    return {"mode": final.legs, "why": why, "what": what}


def plan(human: HumanMotion, robot: Robot, tempo: str | float, legs: str, cap: float, solve: Solve,
         check_options: object | None = None, probe: Callable[[HumanMotion], float] | None = None,
         sketch: Callable[[HumanMotion], RobotMotion] | None = None,
         reached: RobotMotion | None = None,
         replay: Callable[[RobotMotion], HumanMotion] | None = None) -> tuple[RobotMotion, object | None]:
    """The chosen robot motion and its report (None when neither tempo nor legs is ``auto``: one
    attempt, not judged). ``solve(human, legs)``: the robot motion of a legs mode at the human's
    tempo; ``check_options``: the judge's CheckOptions (default: every check with the physics
    playback); ``probe(human)``: the step factor ``steps`` would walk ``human`` with (without
    it, no glide is told apart); ``sketch(human)``: the stance of ``human`` after its solves alone
    (what the comparison with the steps measures; without it, the whole stance; ``solve`` is then
    expected to go on from that sketch); ``reached``: the exact poses of a robot-shaped ``human``
    at its own tempo (:mod:`~.exact`), judged first as its whole body; ``replay(motion)``: a slowed
    robot motion's keypoints in the human's space at the human's tempo (without it, nothing is
    replayed). See the module text for the order of attempts."""
    factors = _factors(tempo, cap, human, robot)
    judging = tempo == "auto" or legs == "auto"
    judge = _judge(robot, check_options) if judging else (lambda motion: None)
    flight = False
    modes = [legs]
    if legs == "auto":
        labels, _ = contact_labels(human)
        flight = has_flight(human, labels)
        modes = auto_legs(human, labels, flight)

    humans: dict[float, HumanMotion] = {}  # one motion per tempo: the probe and the attempt share it

    def at(k: float) -> HumanMotion:
        if k not in humans:
            humans[k] = stretch(human, k)
        return humans[k]

    made: dict[tuple[str, float], RobotMotion] = {}  # solved, not yet judged (the comparison's)
    judged: dict[tuple[str, float], Attempt] = {}

    def attempt(mode: str, k: float) -> Attempt:
        if (mode, k) not in judged:
            motion = made.pop((mode, k)) if (mode, k) in made else solve(at(k), mode)
            motion = motion.with_(meta={"tempo": k})  # what a replay reads it was made at
            judged[(mode, k)] = Attempt(mode, k, motion, judge(motion))
        return judged[(mode, k)]

    def solved(mode: str) -> RobotMotion:
        if (mode, factors[0]) not in made:
            made[(mode, factors[0])] = solve(at(factors[0]), mode)
        return made[(mode, factors[0])]

    tried: list[Attempt] = []
    chosen = None
    nearness: dict | None = None
    skipped: list[dict] = []
    queue = [(m, factors) for m in modes]  # each legs mode with the tempos it is searched over
    probed = False
    if reached is not None and factors[0] == 1.0:  # 0. a robot-shaped motion: its exact poses
        made[("whole", 1.0)] = reached
        tried.append(attempt("whole", 1.0))
        chosen = tried[0] if tried[0].feasible else None
        if chosen is None and tempo == "auto" and not set(tried[0].failed()) & tempo_proof(reached):
            chosen, runs = retimed(tried[0], factors[1:], robot, human.num_frames, judge)  # played slower
            tried += runs
    i = 0
    while chosen is None and i < len(queue):
        mode, tempos = queue[i]
        i += 1
        if mode == "whole" and legs == "auto":
            why = short_shifts(human, robot, labels, max(factors))
            if why is not None:  # no tempo up to the cap gives the static weight shifts time
                skipped.append({"legs": mode, "skipped": why})
                continue
        try:
            if probe is not None and legs == "auto" and mode == "steps" and not probed \
                    and any(m == "stance" for m, _ in queue[i:]):
                probed = True
                glide = _glides(probe(at(factors[0])))
                if glide is not None:  # at this tempo the steps, then the stance; then each slower
                    skipped.append({"legs": mode, "skipped": glide, "set_aside": True})
                    queue[i - 1:] = ([("steps", factors[:1]), ("stance", factors[:1]), ("steps", factors[1:]),
                                      ("stance", factors[1:])] + [q for q in queue[i:] if q[0] != "stance"])
                    i -= 1
                    continue
            if not tempos:
                continue
            if legs == "auto" and mode == "stance" and tempos[0] == factors[0] and nearness is None \
                    and any(m == "steps" and factors[0] in ts for m, ts in queue[i:]):
                # the stance goes first for its tempo: the steps of that tempo are made too, and
                # judged first when nearer
                stood = sketch(at(factors[0])) if sketch is not None else solved("stance")
                nearness = compare(stood, lambda: solved("steps"), factors[0], at(factors[0]), robot)
                nearness["stance_measured"] = "solves" if sketch is not None else "whole"
                if steps_nearer(nearness):
                    walked = attempt("steps", factors[0])
                    tried.append(walked)
                    if walked.feasible:
                        chosen = walked
                        break
            ok, runs = _search(lambda k, mode=mode: attempt(mode, k), tempos, ascending=mode == "steps")
        except PatternError as err:  # a walking pattern this clip cannot give (a foot never down)
            if legs != "auto":
                raise
            skipped.append({"legs": mode, "skipped": str(err)})
            continue
        tried += [a for a in runs if all(a is not b for b in tried)]  # the comparison's steps judged once
        if ok is not None:
            chosen = ok
            break
    # nothing passes: the attempt failing the fewest checks (the later one on a tie: slower, and
    # the stance after the steps, as a user would rather have it)
    nearest = chosen or min(reversed(tried), key=lambda a: len(a.failed()))
    if nearest.factor > 1.0 and nearest.retime_of is None and tempo == "auto" and replay is not None:
        # slowed (a pass, or the nearest to one): re-solved at x1.0, else a pass's poses played faster
        again = replayed(nearest, replay, solve, judge)
        if again is not None:
            tried.append(again)
        if again is not None and again.feasible:
            chosen = again
        elif chosen is not None:
            faster, runs = retimed(chosen, [k for k in factors if k < chosen.factor], robot, human.num_frames, judge)
            tried += runs
            chosen = faster or chosen
    final = chosen or nearest
    meta: dict = {"tempo": float(final.factor), "tempo_policy": str(tempo), "legs_policy": legs,
                  "executable": None if final.report is None else final.feasible,
                  "attempts": [a.record() for a in tried]}
    if skipped:
        meta["legs_skipped"] = skipped
    if nearness:
        meta["nearness"] = {**nearness, "kept": final.legs}
    if final.report is None:
        meta["tempo_reason"] = (f"played x{final.factor:.2f} as asked (--tempo {tempo})" if final.factor != 1.0
                                else "played at the generated tempo (x1.00)")
    elif chosen is None:
        meta["tempo_reason"] = (f"no attempt passes up to the tempo cap x{cap:g}: at x{final.factor:.2f} "
                                f"({final.legs} legs) {_words(final.failed())} still fail")
    elif final.replay_of:
        meta["replayed"] = {"from_tempo": final.replay_of}
        slowed = next(a for a in tried if a.factor == final.replay_of and a.legs == final.legs and not a.replay_of)
        why = ("the smallest slow-down that passes" if slowed.feasible
               else f"the nearest to passing, failing {_words(slowed.failed())}")
        meta["tempo_reason"] = (f"played at the generated tempo (x1.00): the robot's motion slowed x{final.replay_of:.2f} "
                                f"({why}), replayed at the generated tempo and retargeted again, passes the checks")
    elif final.retime_of is not None:
        meta["retimed"] = {"from_tempo": final.retime_of}
        meta["tempo_reason"] = _retime_reason(final, tried)
    elif final.factor == 1.0:
        meta["tempo_reason"] = "played at the generated tempo (x1.00): it passes the checks as generated"
    else:
        base = next(a for a in tried if a.legs == final.legs)
        meta["tempo_reason"] = (f"slowed x{final.factor:.2f}, the smallest slow-down tried that passes "
                                f"(at x{base.factor:.2f} {_words(base.failed())} failed)")
    meta["fallback"] = _fallback(final, legs, flight, tried, robot, skipped, nearness)
    if (chosen is None and final.report is not None and judging
            and needs_full_check(final.report, check_options)):  # the full report of what is returned
        final = Attempt(final.legs, final.factor, final.motion, _judge(robot, check_options, full=True)(final.motion))
    if final.report is not None:  # the report speaks of the motion as annotated
        final.report.figures.update(tempo=meta["tempo"], tempo_reason=meta["tempo_reason"], fallback=meta["fallback"])
    return final.motion.with_(meta=meta), final.report

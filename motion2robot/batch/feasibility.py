"""The batch job run on every clip: read -> retarget -> check -> fidelity (-> save the robot motion).

A *job* is an object with ``setup(config) -> state`` (once per worker process: load the robot,
compile its casadi functions) and ``run(item, state, row, stage) -> None`` (fill one result row;
``stage[0]`` names the step in progress so an exception can say where it happened). This one is
the default; :class:`~motion2robot.batch.worker.BatchConfig` ``job="module:attr"`` selects another.
"""

from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from motion2robot.batch.work import WorkItem


@dataclass(frozen=True)
class FeasibilityState:
    robot: Any
    retarget_options: Any
    check_options: Any


def motion_file_name(item: WorkItem) -> str:
    """Name of a saved robot motion: ``<stem>[_clipN]_<8 hex of the path>.npz`` (the hash keeps
    files of the same name in different folders apart)."""
    digest = hashlib.sha1(item.path.encode()).hexdigest()[:8]
    clip = "" if item.clip in (None, 0) else f"_clip{item.clip}"
    return f"{Path(item.path).stem}{clip}_{digest}.npz"


def _warm_up(robot: Any, options: Any) -> None:
    """Build (and cache) the robot's casadi functions now, not inside the first clip's timing.
    The arguments are passed exactly as ``retarget`` passes them, to hit the same cache entry."""
    try:
        from motion2robot.retarget import prepare  # type: ignore[attr-defined]
    except ImportError:
        try:  # the retargeter's per-process cache of compiled problems
            from motion2robot.retarget.compiled import compiled_problem as prepare
        except ImportError:
            return
    prepare(robot, options.backend)


class FeasibilityJob:
    """Retarget a clip onto ``config.robot`` and check it (kinematic checks, plus the MuJoCo
    rollout unless ``config.physics`` is False)."""

    @staticmethod
    def setup(config: Any) -> FeasibilityState:
        from motion2robot.retarget import RetargetOptions
        from motion2robot.robot import load_robot
        from motion2robot.validate import CheckOptions

        robot = load_robot(config.robot)
        options = RetargetOptions(**dict(getattr(config, "retarget_options", ()) or ()))
        _warm_up(robot, options)
        checks = CheckOptions(physics=config.physics, **dict(getattr(config, "check_options", ())))
        return FeasibilityState(robot, options, checks)

    @staticmethod
    def run(item: WorkItem, state: FeasibilityState, row: dict[str, Any], stage: list[str], config: Any) -> None:
        from motion2robot.motion import read_motion

        stage[0] = "read"
        t0 = time.perf_counter()
        clips = read_motion(item.path, clip=item.clip, **dict(config.read_options))
        if len(clips) != 1:
            raise ValueError(f"expected one clip, the reader returned {len(clips)}")
        row["timings"]["read_s"] = round(time.perf_counter() - t0, 4)
        motion = FeasibilityJob.evaluate(clips[0], state, row, stage)
        if config.save_motions:
            stage[0] = "save"
            out = Path(config.save_motions) / motion_file_name(item)
            row["motion_file"] = str(motion.with_(meta={"feasible": bool(row["feasible"])}).save(out))

    @staticmethod
    def evaluate(human: Any, state: FeasibilityState, row: dict[str, Any], stage: list[str]) -> Any:
        """Retarget and check one clip already in memory, filling ``row`` (clip figures, verdict,
        timings, ``fidelity``); returns the robot motion."""
        from motion2robot.retarget import retarget_and_check
        from motion2robot.validate import check

        t = row["timings"]
        row.update(frames=human.num_frames, fps=human.fps, duration_s=round(human.duration, 4),
                   prompt=human.meta.get("prompt"))
        stage[0] = "retarget"
        t0 = time.perf_counter()
        # the tempo/legs policy judges its attempts with these check options: its report is reused
        motion, report = retarget_and_check(human, state.robot, state.retarget_options, state.check_options)
        if human.meta.get("control_path"):  # a requested trajectory: judged again with it in the meta
            from motion2robot.retarget.control_path import with_control_path

            motion, report = with_control_path(motion, human), None
        t["retarget_s"] = round(time.perf_counter() - t0, 4)
        stage[0] = "check"
        t0 = time.perf_counter()
        if report is None:
            report = check(motion, state.robot, state.check_options)
        t["check_s"] = round(time.perf_counter() - t0, 4)
        row.update(feasible=bool(report.feasible),
                   failed_checks=[name for name, c in report.checks.items() if c.get("ok") is False],
                   reasons=list(report.reasons), figures=dict(report.figures))
        control = {k: v for k, v in report.checks.get("trajectory", {}).items() if k.startswith("control_")}
        if control:
            row["control"] = control
        stage[0] = "fidelity"
        row["fidelity"] = _fidelity(human, motion, state)
        return motion


def _fidelity(human: Any, motion: Any, state: FeasibilityState) -> dict[str, Any]:
    """:func:`~motion2robot.score.fidelity.fidelity` of the clip; a failure there is kept as
    ``{"error": ...}`` (the verdict stands)."""
    from motion2robot.batch.work import one_line
    from motion2robot.score.fidelity import fidelity

    try:
        return fidelity(human, motion, state.robot, fps=state.retarget_options.fps,
                        contact_height=state.check_options.contact_height,
                        contact_speed=state.check_options.contact_speed)
    except Exception as err:  # noqa: BLE001 - a figure missing, not a lost clip
        return {"error": one_line(err)}

"""In-process API for generation loops: retarget and score batches of generated motion without files.

    from motion2robot.api import score, retarget_many

    result = score(samples, robot="op3", lengths=lengths)       # samples: (B, T, 22, 3) or (B, T, 263)
    result.figures.executable_share, result.figures.tempo_median  # the CLI table's row for this batch
    result.samples[3].record["reasons"], result.samples[3].motion  # per sample: batch row, RobotMotion

``motions`` is a numpy array or a torch tensor (on any device, with or without grad; duck-typed:
torch is never imported here) of shape (B, T, 22, 3) HumanML3D joint positions (metres, y up),
MDM's (B, 22, 3, T), or (B, T, 263) HumanML3D features (raw, or normalised: pass ``mean`` and
``std``); or a list of samples of different lengths, or of ``HumanMotion`` clips. A padded batch
needs ``lengths`` (the valid frames of each sample): trailing all-zero frames without ``lengths``
raise :class:`MotionBatchError`, as do shapes and lengths that do not fit (it is a
:class:`~motion2robot.errors.UserError` and a ``ValueError``). A sample with NaN/inf gets an error
record; the others are scored. An unknown robot raises
:class:`~motion2robot.errors.RobotConfigError`.

Every sample goes through ``batch``'s job (retarget with the tempo and legs policy, every check,
the physics playback unless ``physics=False``, the fidelity figures), in worker processes that stay
alive between calls with the same robot and options (``jobs``: how many; 0 runs in this process);
call :func:`close` to stop them. Records are ``batch`` result rows (key ``<tensor>#<index>``,
``read_s`` the conversion time in the caller), so :func:`score`'s figures are the ``score`` CLI's.
Nothing is written to disk (the robot's compiled problems are read from, and on first use written
to, the shared cache ``~/.cache/motion2robot``, as for every command).

:func:`project` (the projection of a human motion onto what the robot can do: retarget, then map
the robot's keypoints back to the human skeleton at the human's scale and tempo) lives in
:mod:`motion2robot.projection` and is re-exported here with its result type.
"""

from __future__ import annotations

import functools
import os
import time
from dataclasses import dataclass
from typing import Any, Sequence

from motion2robot.batch.work import WorkItem
from motion2robot.batch.worker import BatchConfig, base_row
from motion2robot.errors import MotionBatchError
from motion2robot.projection import MotionArrayError, Projection, project
from motion2robot.robot_motion import RobotMotion
from motion2robot.score.batch_input import NAME, to_clips
from motion2robot.score.figures import SetFigures, set_figures
from motion2robot.score.pool import close, run_clips
from motion2robot.score.table import format_table

__all__ = [
    "MotionArrayError", "MotionBatchError", "Projection", "Sample", "ScoreResult", "close", "project",
    "retarget_many", "score",
]


@dataclass(frozen=True)
class Sample:
    """One sample's outcome. record: its ``batch`` result row (``feasible``, ``failed_checks``,
    ``reasons``, ``figures`` with ``tempo`` and ``fallback``, ``fidelity``, ``timings``, ``error``);
    motion: the robot motion (None when the sample could not be retargeted)."""

    index: int
    record: dict[str, Any]
    motion: RobotMotion | None

    @property
    def executable(self) -> bool:
        return self.record.get("error") is None and self.record.get("feasible") is True

    @property
    def error(self) -> str | None:
        return self.record.get("error")


@dataclass(frozen=True)
class ScoreResult:
    """samples: one per input sample, in order; figures: the score table's row for the batch."""

    robot: str
    samples: tuple[Sample, ...]
    figures: SetFigures

    @property
    def records(self) -> list[dict[str, Any]]:
        return [s.record for s in self.samples]

    @property
    def motions(self) -> list[RobotMotion | None]:
        return [s.motion for s in self.samples]

    def table(self) -> str:
        """The table ``motion2robot score`` prints, for this batch."""
        return format_table([self.figures], self.robot)


@functools.lru_cache(maxsize=8)
def _robot_name(robot: str) -> str:
    from motion2robot.robot import load_robot

    return load_robot(robot).name


def _config(robot: str, physics: bool, tempo: str | float, legs: str, tempo_cap: float | None, balance: bool,
            check_options: dict[str, Any] | None) -> BatchConfig:
    from motion2robot.retarget import RetargetOptions
    from motion2robot.validate import CheckOptions

    name = _robot_name(robot)  # RobotConfigError (a UserError) now, not in every record
    retarget = (("tempo", tempo), ("legs", legs), ("balance", balance))
    if tempo_cap is not None:
        retarget += (("tempo_cap", tempo_cap),)
    RetargetOptions(**dict(retarget))  # bad values raise here, once
    checks = tuple(sorted((check_options or {}).items()))
    CheckOptions(**dict(checks))
    return BatchConfig(robot=name, physics=physics, retarget_options=retarget, check_options=checks)


def retarget_many(motions: Any, robot: str = "op3", *, fps: float | None = None, lengths: Any = None,
                  mean: Any = None, std: Any = None, physics: bool = True, tempo: str | float = "auto",
                  legs: str = "auto", tempo_cap: float | None = None, balance: bool = True,
                  check_options: dict[str, Any] | None = None, jobs: int | None = None) -> list[Sample]:
    """Retarget and check every sample of ``motions`` (see the module text) onto ``robot``.

    fps: the samples' frame rate (None: the layout's, 20 for HumanML3D); physics: judge with the
    physics playback; tempo, legs, tempo_cap, balance: as the CLI's ``--tempo`` etc.;
    check_options: CheckOptions fields (thresholds); jobs: worker processes (None: one per core;
    0: this process)."""
    config = _config(robot, physics, tempo, legs, tempo_cap, balance, check_options)
    t0 = time.perf_counter()
    clips = to_clips(motions, lengths=lengths, fps=fps, mean=mean, std=std)
    convert_s = (time.perf_counter() - t0) / max(len(clips), 1)
    items = [WorkItem(NAME, i) for i in range(len(clips))]
    out: list[Sample | None] = [None] * len(clips)
    good = [i for i, c in enumerate(clips) if not isinstance(c, str)]
    for i, c in enumerate(clips):
        if isinstance(c, str):
            row = base_row(items[i], config)
            row["error"] = c
            out[i] = Sample(i, row, None)
    if jobs is None:  # not capped by the batch size: the next call (maybe a bigger batch) reuses the pool
        jobs = os.cpu_count() or 1
    if jobs < 0:
        raise MotionBatchError(f"jobs={jobs}: give 0 (this process) or more workers")
    for i, (row, motion) in zip(good, run_clips([items[i] for i in good], [clips[i] for i in good], config, jobs)):
        row["timings"]["read_s"] = round(convert_s, 4)
        out[i] = Sample(i, row, motion)
    return out  # type: ignore[return-value]


def score(motions: Any, robot: str = "op3", *, fps: float | None = None, lengths: Any = None, name: str = "samples",
          **options: Any) -> ScoreResult:
    """:func:`retarget_many`, then the figures of the ``score`` table for the batch (``name``: its
    set label). ``options``: those of :func:`retarget_many`."""
    samples = retarget_many(motions, robot, fps=fps, lengths=lengths, **options)
    rows = [s.record for s in samples]
    return ScoreResult(rows[0]["robot"] if rows else robot, tuple(samples), set_figures(name, rows))


"""The figures of one set of samples, from its batch result rows.

Counts, the executable share, the failing checks and reasons and the trajectory error come from
:func:`motion2robot.batch.summary.summarize` itself, so they are ``batch-report``'s figures on the
same rows. Added here: the tempo factor of the executable samples (median, p90), the share that
needed an alternative for the legs (``steps`` or ``stance``), the fidelity means (:mod:`~motion2robot.score.fidelity`) and the
throughput. Every figure but the throughput (``cpu_s_per_sample``, ``samples_per_min_per_core``)
is a function of the inputs only.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Sequence

import numpy as np

from motion2robot.batch.summary import Summary, summarize

#: Figures that measure time, not the motions (excluded when comparing runs).
TIMING = ("cpu_s_per_sample", "samples_per_min_per_core")


@dataclass(frozen=True)
class SetFigures:
    """One row of the score table. Shares are fractions of ``samples`` (errors count as not
    executable, as in ``batch-report``); tempo figures are over the executable samples (the
    slow-down they needed; 1.0 = as generated); fidelity means are over the samples solved
    (``fidelity_samples``), keypoint errors in robot cm (``_human_cm``: at human scale; ``_pose_cm``:
    pelvis on pelvis, the posture without the path); ``trajectory_error_m``: mean root error of the samples with a requested
    path (``trajectory_samples``), robot metres; ``top_checks``: (check, samples) most failed
    first; ``top_reason``: the most common reason among the samples not executable, with its
    sample count."""

    name: str
    samples: int
    frames: int
    executable: int
    not_executable: int
    errors: int
    executable_share: float | None
    tempo_median: float | None
    tempo_p90: float | None
    slowed_share: float | None
    fallback_share: float | None
    keypoint_error_cm: float | None
    keypoint_error_human_cm: float | None
    keypoint_error_pose_cm: float | None
    contact_agreement: float | None
    fidelity_samples: int
    trajectory_error_m: float | None
    trajectory_samples: int
    top_checks: tuple[tuple[str, int], ...]
    top_reason: tuple[str, int] | None
    cpu_s_per_sample: float | None
    samples_per_min_per_core: float | None

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["top_checks"] = dict(self.top_checks)
        d["top_reason"] = None if self.top_reason is None else {"example": self.top_reason[0], "samples": self.top_reason[1]}
        return d


def _r(x: float | None, nd: int = 4) -> float | None:
    return None if x is None else round(float(x), nd)


def _mean(xs: Sequence[float], nd: int = 4) -> float | None:
    return _r(float(np.mean(xs)), nd) if xs else None


def set_figures(name: str, rows: Sequence[dict[str, Any]], summary: Summary | None = None) -> SetFigures:
    """The figures of ``rows`` (the rows of one set; ``summary``: their ``summarize`` when known)."""
    s = summary or summarize(rows)
    ok = [r for r in rows if not r.get("error") and r.get("feasible") is True]
    solved = [r for r in rows if not r.get("error") and r.get("feasible") is not None]
    tempo = [float((r.get("figures") or {}).get("tempo", 1.0)) for r in ok]
    n = len(rows)
    fallback = sum(1 for r in solved if (r.get("figures") or {}).get("fallback"))
    fid = [r["fidelity"] for r in solved if isinstance(r.get("fidelity"), dict) and "keypoint_error_m" in r["fidelity"]]
    cpu = [float(r["timings"]["cpu_s"]) for r in rows if (r.get("timings") or {}).get("cpu_s") is not None
           and not r.get("error")]
    cpu_mean = float(np.mean(cpu)) if cpu else None
    failing = summarize([r for r in solved if r.get("feasible") is False], top=1).reasons
    return SetFigures(
        name=name, samples=n, frames=s.frames, executable=s.feasible, not_executable=s.infeasible, errors=s.errors,
        executable_share=_r(s.executable_rate),
        tempo_median=_r(np.median(tempo), 3) if tempo else None,
        tempo_p90=_r(np.percentile(tempo, 90), 3) if tempo else None,
        slowed_share=_r(sum(t > 1.0 for t in tempo) / n) if n else None,
        fallback_share=_r(fallback / n) if n else None,
        keypoint_error_cm=_mean([100 * f["keypoint_error_m"] for f in fid], 2),
        keypoint_error_human_cm=_mean([100 * f["keypoint_error_human_m"] for f in fid], 2),
        keypoint_error_pose_cm=_mean([100 * f["keypoint_error_pose_m"] for f in fid if "keypoint_error_pose_m" in f], 2),
        contact_agreement=_mean([f["contact_agreement"] for f in fid]),
        fidelity_samples=len(fid),
        trajectory_error_m=s.control["mean_error_m"] if s.control else None,
        trajectory_samples=int(s.control["clips"]) if s.control else 0,
        top_checks=s.failed_checks[:3],
        top_reason=(failing[0][2], failing[0][1]) if failing else None,
        cpu_s_per_sample=_r(cpu_mean, 3),
        samples_per_min_per_core=_r(60.0 / cpu_mean, 1) if cpu_mean else None,
    )

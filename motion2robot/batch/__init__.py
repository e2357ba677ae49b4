"""Feasibility of whole data sets: every clip read, retargeted and checked, one JSON line each.

Pipeline: :func:`~motion2robot.batch.work.expand_inputs` (files, folders, manifests -> one
:class:`~motion2robot.batch.work.WorkItem` per clip) -> :func:`~motion2robot.batch.run.plan_batch`
(skip clips already in the results file) -> :func:`~motion2robot.batch.run.run_plan` (a backend:
:mod:`~motion2robot.batch.local` process pool or :mod:`~motion2robot.batch.ray_backend`; the
driver appends each row as it arrives) -> :func:`~motion2robot.batch.summary.summarize`.

Row schema (one JSON object per line; every key always present, ``null`` when unknown):

- ``key``: ``"<absolute path>#<clip>"`` (``#*`` for a file whose clips could not be counted); unique
  per clip, used to resume.
- ``path``, ``clip``: the file and the clip index within it (0 for single-clip files).
- ``frames``, ``fps``, ``duration_s``, ``prompt``: the clip as read (prompt of MDM results).
- ``feasible``: true/false once checked; null when the clip could not be read or solved.
- ``failed_checks``: names of the checks that failed (joint_limits, velocity_limits, acceleration,
  torque_limits, self_collision, ground, balance, rollout, trajectory).
- ``reasons``: the report's one-line reasons; ``figures``: its summary figures (key numbers).
- ``timings``: ``read_s``, ``retarget_s``, ``check_s``, ``total_s`` wall seconds in the worker, and
  ``cpu_s`` the worker's CPU seconds for the clip (differs from total_s when cores are shared).
- ``error``: null, or ``"<stage>: <one-line message>"`` with stage read/retarget/check/save/setup/worker
  when the clip could not be processed.
- ``robot``, ``version``: robot name and motion2robot version; ``motion_file``: the saved robot
  motion (``--save-motions``) or null; ``worker``: ``{"pid", "max_rss_mb"}`` the worker process and
  its peak resident memory so far; ``warnings``: distinct one-line Python warnings raised while
  processing the clip (at most 5); ``fidelity``: null, or the robot motion's fidelity to the human
  (:mod:`motion2robot.score.fidelity`: ``keypoint_error_m``, ``keypoint_error_human_m``,
  ``contact_agreement``, ... or ``{"error": ...}``).
"""

from motion2robot.batch.results import ReadResult, ResultWriter, read_rows
from motion2robot.batch.run import BatchPlan, plan_batch, run_plan
from motion2robot.batch.summary import Summary, format_summary, summarize
from motion2robot.batch.work import Expansion, WorkItem, expand_inputs
from motion2robot.batch.worker import BatchConfig

__all__ = [
    "BatchConfig", "BatchPlan", "Expansion", "ReadResult", "ResultWriter", "Summary", "WorkItem",
    "expand_inputs", "format_summary", "plan_batch", "read_rows", "run_plan", "summarize",
]

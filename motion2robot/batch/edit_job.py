"""The batch job of ``batch --pairs``: read an edit pair, retarget it keeping what the edit did not
change (:func:`motion2robot.edit.retarget_edit`), check both robot motions. The row's verdict is
the edited motion's; ``row["edit"]`` holds the source's verdict, the parts and joints changed and
what the edit broke or fixed."""

from __future__ import annotations

import time
from typing import Any

from motion2robot.batch.feasibility import FeasibilityJob, FeasibilityState
from motion2robot.batch.pairs import SEPARATOR
from motion2robot.batch.work import WorkItem
from motion2robot.errors import InputFileError


def read_pair(path: str, read_options: dict) -> tuple[Any, Any]:
    """(source, edit) HumanMotions of a pair item's path."""
    from motion2robot.motion import read_motion

    if SEPARATOR in path:
        src, edit = path.split(SEPARATOR)
        return read_motion(src, clip=0, **read_options)[0], read_motion(edit, clip=0, **read_options)[0]
    roles = {c.meta.get("role"): c for c in read_motion(path, **read_options)}
    if "source" not in roles or "edited" not in roles:
        raise InputFileError(f"{path}: holds no (source, edited) pair; give an editor result file with pose and "
                             "pose_source, or a manifest of SOURCE<TAB>EDIT lines")
    return roles["source"], roles["edited"]


class EditJob(FeasibilityJob):
    """Retarget an edit pair and check both motions."""

    @staticmethod
    def run(item: WorkItem, state: FeasibilityState, row: dict[str, Any], stage: list[str], config: Any) -> None:
        from motion2robot.edit import retarget_edit
        from motion2robot.validate import check

        t = row["timings"]
        stage[0] = "read"
        t0 = time.perf_counter()
        source, edit = read_pair(item.path, dict(config.read_options))
        row.update(frames=source.num_frames, fps=source.fps, duration_s=round(source.duration, 4),
                   prompt=edit.meta.get("prompt"))
        t["read_s"] = round(time.perf_counter() - t0, 4)
        stage[0] = "retarget"
        t0 = time.perf_counter()
        result = retarget_edit(source, edit, state.robot, state.retarget_options, name=item.path.replace(SEPARATOR, " + "))
        t["retarget_s"] = round(time.perf_counter() - t0, 4)
        stage[0] = "check"
        t0 = time.perf_counter()
        rep_src = check(result.source, state.robot, state.check_options)
        rep = check(result.edited, state.robot, state.check_options)
        t["check_s"] = round(time.perf_counter() - t0, 4)
        row.update(feasible=bool(rep.feasible),
                   failed_checks=[name for name, c in rep.checks.items() if c.get("ok") is False],
                   reasons=list(rep.reasons), figures=dict(rep.figures))
        row["edit"] = {"source_feasible": bool(rep_src.feasible), "human_parts_changed": sorted(result.human),
                       "robot_joints_changed": sorted(result.robot),
                       "breaks": [r for r in rep.reasons if r not in rep_src.reasons],
                       "fixes": [r for r in rep_src.reasons if r not in rep.reasons],
                       "balance_override": result.info.get("balance_override")}
        if config.save_motions:
            from pathlib import Path

            from motion2robot.batch.feasibility import motion_file_name

            stage[0] = "save"
            stem = Path(config.save_motions) / motion_file_name(item)
            row["motion_file"] = str(result.edited.with_(meta={"feasible": bool(rep.feasible)}).save(
                stem.with_name(stem.stem + "_edited.npz")))
            row["edit"]["source_motion_file"] = str(result.source.with_(
                meta={"feasible": bool(rep_src.feasible)}).save(stem.with_name(stem.stem + "_source.npz")))

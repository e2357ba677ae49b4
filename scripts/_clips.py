"""The dev clips the benchmark scripts iterate over: one (name, HumanMotion) per readable clip of a
folder, as ``batch`` expands it (files, then clips of multi-clip files); unreadable ones are
printed as skipped, not part of any figure."""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

from motion2robot.batch.work import expand_inputs
from motion2robot.motion import read_motion
from motion2robot.motion.human import HumanMotion


def readable_clips(folder: str | Path, limit: int | None = None,
                   only: list[str] | None = None) -> Iterator[tuple[str, HumanMotion]]:
    """(display name, clip) of the first ``limit`` work items of ``folder`` that read (with
    ``only``: those whose display name contains one of its strings)."""
    for item in list(expand_inputs([str(folder)]).items)[:limit]:
        name = Path(item.path).name + ("" if item.clip in (None, 0) else f"#{item.clip}")
        if only and not any(o in name for o in only):
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                human = read_motion(item.path, clip=item.clip)[0]
        except Exception as err:  # noqa: BLE001 - unreadable clips are not part of the figure
            print(f"  skip {name}: {str(err).splitlines()[0][:100]}")
            continue
        yield name, human


#: ../shared/motions beside the repository.
SHARED = Path(__file__).resolve().parents[2] / "shared" / "motions"


def clips_parser(doc: str) -> argparse.ArgumentParser:
    """The arguments every clip benchmark takes: --robot, --motions, --limit, --only, --csv."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--robot", default="op3")
    ap.add_argument("--motions", default=str(SHARED))
    ap.add_argument("--limit", type=int, default=None, help="first N clips only")
    ap.add_argument("--only", action="append", default=None, metavar="TEXT",
                    help="only the clips whose name contains TEXT (repeatable)")
    ap.add_argument("--csv", default=None)
    return ap


def motions_missing(folder: str | Path) -> bool:
    """True (with a message on stderr) when the motions folder is absent."""
    if Path(folder).is_dir():
        return False
    print(f"no motions folder at {folder}", file=sys.stderr)
    return True

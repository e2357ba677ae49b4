"""The format table: one list feeding detection, reading, batch's folder scan and the CLI help."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2robot.batch.work import MOTION_EXTENSIONS, expand_inputs
from motion2robot.cli import build_parser
from motion2robot.motion import FORMATS, detect_format, read_motion
from motion2robot.motion.formats import BY_NAME, SCAN_SUFFIXES, SINGLE_CLIP_SUFFIXES, TABLE, formats_using
from tests.test_motion_support import walking_yup


def test_every_format_has_an_importable_reader_and_a_summary() -> None:
    assert FORMATS == tuple(f.name for f in TABLE) and len(set(FORMATS)) == len(FORMATS)
    for f in TABLE:
        assert callable(f.read_function()), f.name
        assert f.summary and all(s.startswith(".") for s in f.suffixes), f.name


def test_batch_scans_the_table_suffixes_and_counts_single_clip_files() -> None:
    assert MOTION_EXTENSIONS == SCAN_SUFFIXES
    assert set(SINGLE_CLIP_SUFFIXES) == {".bvh", ".amc"}  # .npy/.npz hold batches, a .pkl an edit triple


def test_cli_help_lists_every_format_and_the_options_they_take() -> None:
    text = build_parser()._subparsers._group_actions[0].choices["inspect"].format_help()
    flat = " ".join(text.split())
    for f in TABLE:
        assert f"{f.name}:" in flat
    assert "bvh" in formats_using("name_map") and "asf_amc" in formats_using("skeleton")


def test_detection_reading_and_scan_agree_on_a_folder(tmp_path: Path) -> None:
    np.save(tmp_path / "a.npy", walking_yup(20))
    np.savez(tmp_path / "b.npz", joints=walking_yup(21), fps=20.0)
    (tmp_path / "notes.md").write_text("not a motion")
    assert detect_format(tmp_path / "a.npy") == "humanml3d_joints" and detect_format(tmp_path / "b.npz") == "npz"
    assert [m.num_frames for m in read_motion(tmp_path)] == [20, 21]
    items = expand_inputs([tmp_path]).items
    assert [Path(i.path).name for i in items] == ["a.npy", "b.npz"]
    assert BY_NAME["humanml3d_joints"].npy and not BY_NAME["bvh"].npy

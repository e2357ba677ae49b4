"""``motion2robot inspect``: the block per clip and the --plot picture."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motion2robot.cli import main
from tests._shared import MOTIONS, requires_shared
from tests.test_motion_support import walking_yup


def test_inspect_synthetic_clip_and_plot(tmp_path: Path, capsys) -> None:
    np.save(tmp_path / "walk.npy", walking_yup(40))
    png = tmp_path / "walk.png"
    assert main(["inspect", str(tmp_path / "walk.npy"), "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "format humanml3d_joints (detected), 1 clip" in out
    assert "40 at 20 fps = 2.00 s" in out and "height      1.6" in out
    assert "up axis     y" in out and "contacts    left" in out and "detected (height" in out
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


def test_inspect_format_override_is_reported(tmp_path: Path, capsys) -> None:
    np.save(tmp_path / "walk.npy", walking_yup(40))
    assert main(["inspect", str(tmp_path / "walk.npy"), "--format", "humanml3d_joints", "--source-fps", "30"]) == 0
    out = capsys.readouterr().out
    assert "(given)" in out and "40 at 30 fps" in out and "file says 20 fps" in out


@requires_shared
@pytest.mark.parametrize("rel,expect", [
    ("mdm_results/mdm_walk_pickup_results.npy", ['3 clips', '"the person walked forward and is picking up his toolbox."']),
    ("humanml3d_vecs/011673.npy", ["263-d contact channels", "features    raw"]),
    ("bvh/cmu_01_01.bvh", ["units       cmu", "dropped     frame 0", "2751 at 120 fps = 22.93 s"]),
    ("bvh/bandai_walk_normal_001.bvh", ["skeleton    bandai_namco", "units       cm", "along y"]),
])
def test_inspect_real_files(rel: str, expect: list[str], capsys) -> None:
    assert main(["inspect", str(MOTIONS / rel)]) == 0
    out = capsys.readouterr().out
    for e in expect:
        assert e in out, (e, out)
    heights = [float(line.split()[1]) for line in out.splitlines() if line.strip().startswith("height")]
    assert heights and all(1.4 <= h <= 2.0 for h in heights)


@requires_shared
def test_inspect_clip_selection(capsys) -> None:
    assert main(["inspect", str(MOTIONS / "mdm_results/mdm_throw_ball_results.npy"), "--clip", "4"]) == 0
    out = capsys.readouterr().out
    assert "1 clip" in out and "clip 4 (1 of 1)" in out and '"A person throws a ball"' in out
    assert main(["inspect", str(MOTIONS / "mdm_results/mdm_throw_ball_results.npy"), "--clip", "40"]) == 2
    assert "out of range" in capsys.readouterr().err

"""The self-contained HTML feasibility report and its plots, on the real checks."""

from __future__ import annotations

import base64
import io
import re

import numpy as np
import pytest

from motion2robot.robot import load_robot
from motion2robot.validate import check
from motion2robot.viz.html_report import key_frames, render_html, worst_frame, write_html_report
from motion2robot.viz.plots import convex_outline, figure_png, plot_ratio
from tests.test_viz_render import standing_human, wave_motion

PLOT_ALTS = ("joint angles against limits", "joint speeds", "torque ratios",
             "CoM and ZMP against the support polygon", "foot heights and contact phases")


@pytest.fixture(scope="module")
def robot():
    return load_robot("op3")


@pytest.fixture(scope="module")
def case(robot):
    motion = wave_motion(robot, frames=40, meta={"source": "wave.npy", "prompt": "wave both arms <fast>"})
    return motion, check(motion, robot)


def _images(text: str) -> list[tuple[bytes, str]]:
    return [(base64.b64decode(d), alt) for d, alt in re.findall(r'<img src="data:image/png;base64,([^"]+)" alt="([^"]*)"', text)]


def test_report_page_has_verdict_reasons_plots_and_key_frames(robot, case, tmp_path):
    from PIL import Image

    motion, report = case
    assert not report.feasible  # the arms swing faster than the servos allow
    path = write_html_report(report, motion, robot, tmp_path / "sub" / "report.html", human=standing_human(40))
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and "<style>" in text
    assert "NOT FEASIBLE" in text and 'class="verdict-table"' in text
    for name, res in report.checks.items():
        assert f"<td>{name}</td>" in text
    assert "velocity_limits</td><td class=\"failc\">FAIL" in text
    assert "wave both arms &lt;fast&gt;" in text  # escaped
    for reason in report.reasons[:2]:
        assert reason.split(",")[0] in text
    images = _images(text)
    alts = [alt for _, alt in images]
    for alt in PLOT_ALTS:
        assert alts.count(alt) == 1
    strip = [a for a in alts if a.startswith("key frame")]
    assert [a.split()[2] for a in strip] == ["first", "worst", "last"]
    assert "(frame 0)" in strip[0] and "(frame 39)" in strip[2]
    for png, alt in images:
        img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
        assert img.std() > 10, alt  # a real picture, not a blank one
    assert "http" not in re.sub(r'data:image/png;base64,[^"]+', "", text).split("<body>")[1]  # self-contained


def test_report_without_key_frames_or_series_still_renders(robot, case):
    motion, report = case

    class Bare:
        feasible, checks, reasons, figures, series = True, {"joint_limits": {"ok": True, "frames": []},
                                                            "rollout": {"ok": True, "skipped": "--no-physics", "frames": []}}, [], {}, {}

    text = render_html(Bare(), motion, robot, keyframes=False)
    assert "FEASIBLE" in text and "NOT FEASIBLE" not in text and "every check passed" in text
    assert "<td>skipped</td>" not in text and ">skipped</td><td>&ndash;</td><td>--no-physics" in text
    assert _images(text) == []


def test_worst_frame_is_where_most_checks_fail(case):
    motion, report = case

    class R:
        checks = {"torque_limits": {"ok": False, "frames": [3, 4, 5]}, "balance": {"ok": False, "frames": [5, 6]},
                  "joint_limits": {"ok": True, "frames": [9]}, "trajectory": {"ok": False, "frames": [7]}}
        series = {"support_margin": np.linspace(0.1, -0.1, 10)}

    assert worst_frame(R(), 10) == 5
    R.checks = {}
    assert worst_frame(R(), 10) == 9  # no failure: smallest support margin
    assert [k for k, _ in key_frames(report, motion.num_frames)] == ["first", "worst", "last"]
    assert 0 <= key_frames(report, motion.num_frames)[1][1] < motion.num_frames


def test_ratio_plot_png_and_outline():
    ratio = np.abs(np.sin(np.linspace(0, 6, 50)))[:, None] * np.array([0.5, 1.4, 0.2])
    png = figure_png(plot_ratio(ratio, ["a", "b", "c"], 20.0, "t", "y"))
    assert png.startswith(b"\x89PNG") and len(png) > 5000
    o = convex_outline(np.array([[1, 1], [0, 0], [1, 0], [0, 1.0]]))
    assert len(o) == 5 and np.allclose(o[0], o[-1])
    edges = np.linalg.norm(np.diff(o, axis=0), axis=1)
    assert np.allclose(edges, 1.0)  # walks around the square, no diagonal


def test_convex_hull_of_two_feet():
    from motion2robot.viz.plots import convex_hull

    left = np.array([[0, 0.05], [0.1, 0.05], [0.1, 0.1], [0, 0.1]])
    right = left - [0, 0.15]
    h = convex_hull(np.vstack([left, right, [[0.05, 0.0]]]))  # an inner point is dropped
    assert len(h) == 5 and np.allclose(h[0], h[-1])
    assert {tuple(p) for p in h[:-1].round(6)} == {(0, -0.1), (0.1, -0.1), (0.1, 0.1), (0, 0.1)}

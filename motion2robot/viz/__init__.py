"""See it: the MuJoCo viewer, offscreen-rendered videos and the HTML feasibility report.

- :mod:`~motion2robot.viz.gl`: OpenGL backend choice (EGL without a display) and its error.
- :mod:`~motion2robot.viz.scene`: the :class:`Playable` (robot poses + scaled human skeleton +
  failing frames) and the user geoms drawn into MuJoCo scenes.
- :mod:`~motion2robot.viz.camera`: follow / fixed camera tracks.
- :mod:`~motion2robot.viz.render`: offscreen frames, MP4 / GIF writing.
- :mod:`~motion2robot.viz.playback` and :mod:`~motion2robot.viz.viewer`: the interactive viewer.
- :mod:`~motion2robot.viz.plots` and :mod:`~motion2robot.viz.html_report`: the report page.

Submodules are imported on use (matplotlib and OpenGL load only when needed).
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "write_html_report": "motion2robot.viz.html_report",
    "render_frames": "motion2robot.viz.render",
    "write_video": "motion2robot.viz.render",
    "OffscreenRenderer": "motion2robot.viz.render",
    "make_playable": "motion2robot.viz.scene",
    "Playable": "motion2robot.viz.scene",
    "SceneOptions": "motion2robot.viz.scene",
    "Playback": "motion2robot.viz.playback",
    "play_in_viewer": "motion2robot.viz.viewer",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'motion2robot.viz' has no attribute {name!r}")

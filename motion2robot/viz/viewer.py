"""The interactive MuJoCo viewer (passive mode): real-time playback of a
:class:`~motion2robot.viz.scene.Playable` with pause/step/loop driven by :class:`Playback`.

Needs a display (``DISPLAY``/``WAYLAND_DISPLAY``); without one, render a video instead.
"""

from __future__ import annotations

import time

import mujoco

from motion2robot.errors import UserError
from motion2robot.viz.gl import gl_error, has_display
from motion2robot.viz.playback import HELP, Playback
from motion2robot.viz.render import playable_camera
from motion2robot.viz.scene import Playable


def play_in_viewer(model: mujoco.MjModel, play: Playable, *, loop: bool = True, speed: float = 1.0,
                   camera: str = "follow", stop_after: float | None = None) -> Playback:
    """Open the viewer on ``model`` (the robot's world) and play until the window is closed.

    The camera starts framing the subjects; with ``follow`` its look-at point keeps tracking them
    while the mouse still controls distance and angles. ``stop_after`` (s of wall clock) closes
    the window by itself (smoke tests). Returns the final playback state."""
    if not has_display():
        raise UserError("no display (DISPLAY is not set) for the viewer; "
                        "render a video instead with --render out.mp4 (or out.gif)")
    try:
        import mujoco.viewer
    except Exception as err:
        raise gl_error("glfw", err) from err
    pb = Playback(play.num_frames, play.fps, loop=loop, speed=speed, failing=play.failing)
    track = playable_camera(play, camera)
    data = mujoco.MjData(model)
    try:
        handle = mujoco.viewer.launch_passive(model, data, key_callback=pb.on_key,
                                              show_left_ui=False, show_right_ui=False)
    except Exception as err:  # no GLFW / no GL on the display
        raise gl_error("glfw", err) from err
    with handle as v:
        with v.lock():
            track.apply(v.cam, 0)
        last = start = time.perf_counter()
        while v.is_running() and (stop_after is None or last - start < stop_after):
            now = time.perf_counter()
            f = pb.tick(now - last)
            last = now
            data.qpos[:] = play.qpos[f]
            mujoco.mj_forward(model, data)
            with v.lock():
                if camera == "follow":
                    v.cam.lookat[:] = track.lookat[f]
                v.user_scn.ngeom = 0
                play.decorate(v.user_scn, model, f)
            v.set_texts([(mujoco.mjtFontScale.mjFONTSCALE_150, mujoco.mjtGridPos.mjGRID_TOPLEFT,
                          play.label(f), pb.status()),
                         (None, mujoco.mjtGridPos.mjGRID_BOTTOMLEFT, play.title, HELP)])  # locks by itself
            v.sync()
            time.sleep(max(0.0, 1.0 / play.fps - (time.perf_counter() - now)))
    return pb

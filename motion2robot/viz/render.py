"""Offscreen rendering (no display needed) of a :class:`~motion2robot.viz.scene.Playable` to
frames, and writing them as MP4 (imageio + imageio-ffmpeg, optional extra ``video``) or GIF (Pillow).

Frames are (H, W, 3) uint8 RGB arrays, top row first.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Iterable, Iterator, Sequence

import mujoco
import numpy as np

from motion2robot.errors import UserError
from motion2robot.viz.camera import CameraTrack, camera_track
from motion2robot.viz.gl import gl_error, make_context, select_backend
from motion2robot.viz.scene import Playable

VIDEO_SUFFIXES = (".mp4", ".gif")


class OffscreenRenderer:
    """Renders a model's scene into arrays through an offscreen OpenGL context (see viz.gl).

    ``pretty`` turns on shadows and floor reflections (about 5x slower with software GL).
    Use as a context manager, or call :meth:`close`."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int, *, backend: str | None = None,
                 max_geom: int = 4000, pretty: bool = False):
        self.model, self.width, self.height = model, int(width), int(height)
        model.vis.global_.offwidth = max(int(model.vis.global_.offwidth), self.width)
        model.vis.global_.offheight = max(int(model.vis.global_.offheight), self.height)
        self.backend = backend or select_backend()
        self._gl = make_context(self.width, self.height, self.backend)
        try:
            font = mujoco.mjtFontScale.mjFONTSCALE_100 if self.width < 560 else mujoco.mjtFontScale.mjFONTSCALE_150
            self._ctx = mujoco.MjrContext(model, font)
            mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._ctx)
        except Exception as err:  # mujoco.FatalError when the context is unusable
            self._gl.free()
            raise gl_error(self.backend, err) from err
        self.scene = mujoco.MjvScene(model, maxgeom=max_geom)
        self.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = int(pretty)
        self.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = int(pretty)
        self.option = mujoco.MjvOption()
        self.camera = mujoco.MjvCamera()
        self._rect = mujoco.MjrRect(0, 0, self.width, self.height)

    def render(self, data: mujoco.MjData, decorate: Callable[[mujoco.MjvScene], None] | None = None,
               text: str = "", title: str = "") -> np.ndarray:
        """One (H, W, 3) uint8 image of ``data`` seen from :attr:`camera`; ``decorate`` may add
        user geoms; ``text`` goes top left, ``title`` bottom left."""
        self._gl.make_current()
        mujoco.mjv_updateScene(self.model, data, self.option, None, self.camera,
                               mujoco.mjtCatBit.mjCAT_ALL, self.scene)
        if decorate is not None:
            decorate(self.scene)
        mujoco.mjr_render(self._rect, self.scene, self._ctx)
        font = mujoco.mjtFont.mjFONT_NORMAL
        if text:
            mujoco.mjr_overlay(font, mujoco.mjtGridPos.mjGRID_TOPLEFT, self._rect, text, "", self._ctx)
        if title:
            mujoco.mjr_overlay(font, mujoco.mjtGridPos.mjGRID_BOTTOMLEFT, self._rect, title, "", self._ctx)
        img = np.empty((self.height, self.width, 3), dtype=np.uint8)
        mujoco.mjr_readPixels(img, None, self._rect, self._ctx)
        return np.flipud(img).copy()

    def close(self) -> None:
        if getattr(self, "_ctx", None) is not None:
            self._gl.make_current()
            self._ctx.free()
            self._ctx = None
            self._gl.free()

    def __enter__(self) -> "OffscreenRenderer":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def playable_camera(play: Playable, mode: str = "follow", aspect: float = 4 / 3) -> CameraTrack:
    """Camera following (or framing the whole path of) the robot root and the human pelvis."""
    tracks = [play.qpos[:, :3]]
    if play.human is not None:
        tracks.append(play.human[:, 0, :])
    return camera_track(tracks, play.height, play.fps, mode, aspect=aspect)


def output_frames(n_frames: int, fps: float, out_fps: float | None) -> np.ndarray:
    """Indices of the motion frames shown at ``out_fps`` (all frames when None or >= fps)."""
    if out_fps is None or out_fps >= fps:
        return np.arange(n_frames)
    n_out = max(1, int(np.floor((n_frames - 1) / fps * out_fps)) + 1)
    return np.minimum(np.round(np.arange(n_out) * fps / out_fps).astype(int), n_frames - 1)


def render_frames(model: mujoco.MjModel, play: Playable, frames: Iterable[int], *, size: tuple[int, int] = (640, 480),
                  camera: str = "follow", labels: bool = True, pretty: bool = False) -> Iterator[np.ndarray]:
    """Yield one image per index in ``frames`` of ``play`` rendered in ``model`` (the robot's world,
    see ``motion2robot.robot.world.make_world``); size is (width, height) pixels."""
    width, height = size
    track = playable_camera(play, camera, aspect=width / height)
    data = mujoco.MjData(model)
    with OffscreenRenderer(model, width, height, pretty=pretty) as r:
        for f in frames:
            f = int(f)
            data.qpos[:] = play.qpos[f]
            mujoco.mj_forward(model, data)
            track.apply(r.camera, f)
            yield r.render(data, lambda scn: play.decorate(scn, model, f),
                           text=play.label(f) if labels else "", title=play.title if labels else "")


def write_video(frames: Iterable[np.ndarray], path: str | Path, fps: float) -> Path:
    """Write frames to ``.mp4`` (H.264 via imageio-ffmpeg) or ``.gif`` (Pillow); returns the path."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in VIDEO_SUFFIXES:
        raise UserError(f"{path}: unknown video type {suffix or '(none)'}; use a name ending in .mp4 or .gif")
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".gif":
        return _write_gif(frames, path, fps)
    return _write_mp4(frames, path, fps)


def _write_gif(frames: Iterable[np.ndarray], path: Path, fps: float) -> Path:
    from PIL import Image

    images = [Image.fromarray(f) for f in frames]
    if not images:
        raise ValueError("no frames to write")
    duration = max(20, int(round(1000 / fps)))  # GIF delays are in 10 ms units; browsers clamp < 20 ms
    images[0].save(path, save_all=True, append_images=images[1:], duration=duration, loop=0, optimize=False)
    return path


def _write_mp4(frames: Iterable[np.ndarray], path: Path, fps: float) -> Path:
    try:
        import imageio.v2 as imageio
        import imageio_ffmpeg  # noqa: F401  (ships the ffmpeg binary)
    except ImportError as err:
        raise UserError(f"{path}: writing MP4 needs imageio and imageio-ffmpeg; "
                        "pip install 'motion2robot[video]' (or imageio imageio-ffmpeg), or write a .gif") from err
    writer = imageio.get_writer(str(path), fps=fps, codec="libx264", quality=7, macro_block_size=2,
                                ffmpeg_log_level="error", pixelformat="yuv420p")
    try:
        for f in frames:
            writer.append_data(f)
    finally:
        writer.close()
    return path


def parse_size(text: str) -> tuple[int, int]:
    """'640x480' -> (640, 480); raises UserError on bad input (even sizes for MP4)."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise UserError(f"--size {text!r}: expected WIDTHxHEIGHT in pixels, e.g. 640x480") from None
    if not (16 <= w <= 4096 and 16 <= h <= 4096):
        raise UserError(f"--size {text!r}: width and height must be between 16 and 4096 pixels")
    return w - w % 2, h - h % 2


def side_by_side(images: Sequence[np.ndarray], gap: int = 4) -> np.ndarray:
    """Concatenate equally tall images horizontally with a white gap (for key-frame strips)."""
    h = images[0].shape[0]
    sep = np.full((h, gap, 3), 255, dtype=np.uint8)
    parts: list[np.ndarray] = []
    for i, im in enumerate(images):
        parts += ([sep] if i else []) + [im]
    return np.concatenate(parts, axis=1)

"""OpenGL backend selection for MuJoCo rendering, and the one error shown when it fails.

MuJoCo renders through one of three backends (``MUJOCO_GL``): ``glfw`` (needs a display),
``egl`` (headless, GPU or Mesa's software EGL) and ``osmesa`` (headless, software). With no
``MUJOCO_GL`` set and no display we pick ``egl``. The context is created here directly from the
chosen backend module, so it works even when ``mujoco`` was imported before the variable was set.
"""

from __future__ import annotations

import importlib
import os
from typing import Any, Mapping

from motion2robot.errors import UserError

HEADLESS_BACKENDS = ("egl", "osmesa")
BACKENDS = ("glfw",) + HEADLESS_BACKENDS
_ALIASES = {"": None, "enable": None, "enabled": None, "on": None, "true": None, "1": None, "glx": "glfw"}

#: The Debian packages each backend needs (the README lists the same).
DEBIAN_PACKAGES = {
    "egl": "libegl1 libgl1",
    "osmesa": "libosmesa6 libgl1",
    "glfw": "libglfw3 libgl1 (and a display)",
}


def has_display(env: Mapping[str, str] | None = None) -> bool:
    env = os.environ if env is None else env
    return bool(env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"))


def select_backend(env: Mapping[str, str] | None = None) -> str:
    """The backend to use: ``MUJOCO_GL`` when set, else ``glfw`` with a display, ``egl`` without."""
    env = os.environ if env is None else env
    raw = env.get("MUJOCO_GL", "").strip().lower()
    name = _ALIASES.get(raw, raw)
    if name is None:
        return "glfw" if has_display(env) else "egl"
    if name in ("disable", "disabled", "off", "false", "0"):
        raise UserError(f"MUJOCO_GL={raw}: rendering is disabled; unset MUJOCO_GL or set it to egl, osmesa or glfw")
    if name not in BACKENDS:
        raise UserError(f"MUJOCO_GL={raw}: unknown OpenGL backend; set it to egl, osmesa or glfw")
    return name


def prefer_headless() -> None:
    """Set ``MUJOCO_GL=egl`` when there is no display and the user did not choose a backend.

    Call before the first ``import mujoco`` where possible (then ``mujoco.Renderer`` uses it too)."""
    if not os.environ.get("MUJOCO_GL") and not has_display():
        os.environ["MUJOCO_GL"] = "egl"


def import_mujoco() -> Any:
    """``import mujoco``, turning a failure of the backend named by ``MUJOCO_GL`` (mujoco loads it
    at import time, e.g. ``MUJOCO_GL=osmesa`` without libOSMesa) into the one-line :func:`gl_error`.

    The CLI calls this before importing the commands (which import mujoco)."""
    try:
        import mujoco
    except ImportError:
        raise
    except Exception as err:  # AttributeError/OSError from PyOpenGL when the GL library is missing
        backend = os.environ.get("MUJOCO_GL", "").strip().lower()
        raise gl_error(backend if backend in BACKENDS else "egl", err) from err
    return mujoco


def gl_error(backend: str, detail: Any) -> UserError:
    """The one-line error for a backend that failed, naming the Debian packages it needs."""
    detail = " ".join(str(detail).split())[:200] or type(detail).__name__
    other = "egl" if backend != "egl" else "osmesa"
    return UserError(
        f"cannot start OpenGL rendering with MUJOCO_GL={backend} ({detail}); "
        f"install the Debian packages {DEBIAN_PACKAGES[backend]} (apt-get install "
        f"{DEBIAN_PACKAGES[backend].split(' (')[0]}) or try MUJOCO_GL={other}")


def make_context(width: int, height: int, backend: str | None = None) -> Any:
    """A current OpenGL context of at least ``width`` x ``height`` pixels for offscreen rendering.

    Raises :class:`UserError` (see :func:`gl_error`) when the backend cannot start."""
    backend = backend or select_backend()
    try:
        if backend == "glfw" and not has_display():
            raise RuntimeError("no DISPLAY for glfw")
        module = importlib.import_module(f"mujoco.{backend}")
        ctx = module.GLContext(int(width), int(height))
        ctx.make_current()
    except UserError:
        raise
    except Exception as err:  # ImportError, OSError, RuntimeError, GLError, AttributeError: all mean "no GL"
        raise gl_error(backend, err) from err
    return ctx

"""OpenGL backend choice and the one-line error naming the Debian packages."""

from __future__ import annotations

import subprocess
import sys

import pytest

from motion2robot.errors import UserError
from motion2robot.viz.gl import gl_error, select_backend


def test_backend_defaults_to_egl_without_a_display():
    assert select_backend({}) == "egl"
    assert select_backend({"DISPLAY": ":0"}) == "glfw"
    assert select_backend({"WAYLAND_DISPLAY": "wayland-0"}) == "glfw"
    assert select_backend({"MUJOCO_GL": "OSMesa", "DISPLAY": ":0"}) == "osmesa"
    assert select_backend({"MUJOCO_GL": "egl"}) == "egl"


@pytest.mark.parametrize("value", ["vulkan", "off"])
def test_bad_or_disabled_backend_is_a_user_error(value):
    with pytest.raises(UserError, match="MUJOCO_GL"):
        select_backend({"MUJOCO_GL": value})


def test_gl_error_is_one_line_and_names_the_packages():
    msg = str(gl_error("egl", "EGL_NOT_INITIALIZED\n(0x3001)"))
    assert "\n" not in msg
    assert "libegl1" in msg and "libgl1" in msg and "MUJOCO_GL=osmesa" in msg
    assert "libosmesa6" in str(gl_error("osmesa", ImportError("no libOSMesa")))


def test_a_backend_that_cannot_start_gives_the_package_hint():
    """OSMesa is not installed on the CI machine; elsewhere it may work, then there is no error.
    Runs in a subprocess: PyOpenGL binds its platform once per process."""
    code = ("import sys\nfrom motion2robot.errors import UserError\nfrom motion2robot.viz.gl import make_context\n"
            "try:\n    make_context(32, 32, 'osmesa')\nexcept UserError as e:\n    print(e); sys.exit(2)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    if out.returncode == 0:
        pytest.skip("OSMesa works on this machine")
    assert out.returncode == 2, out.stderr
    line = out.stdout.strip()
    assert line.count("\n") == 0 and "libosmesa6" in line and "MUJOCO_GL=osmesa" in line


def test_importing_mujoco_with_a_broken_backend_gives_the_package_hint():
    code = ("import sys\nfrom motion2robot.errors import UserError\nfrom motion2robot.viz.gl import import_mujoco\n"
            "try:\n    import_mujoco()\nexcept UserError as e:\n    print(e); sys.exit(2)\n")
    env = {**__import__("os").environ, "MUJOCO_GL": "osmesa"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, env=env)
    if out.returncode == 0:
        pytest.skip("OSMesa works on this machine")
    assert out.returncode == 2, out.stderr
    assert "libosmesa6" in out.stdout and out.stdout.strip().count("\n") == 0

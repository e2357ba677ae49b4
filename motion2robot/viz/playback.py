"""Real-time playback state (frame index, pause, step, loop, speed) for the viewer, with no window.

:class:`Playback` is driven by wall-clock ticks and key presses (GLFW key codes, as the MuJoCo
viewer's ``key_callback`` delivers them); the viewer only reads :attr:`Playback.frame`. Methods are
thread-safe: key callbacks arrive on the viewer's UI thread.
"""

from __future__ import annotations

import threading
from typing import Iterable

#: GLFW key codes used by the viewer.
KEY_SPACE, KEY_RIGHT, KEY_LEFT, KEY_DOWN, KEY_UP, KEY_HOME = 32, 262, 263, 264, 265, 268
KEY_F, KEY_L = 70, 76
SPEEDS = (0.125, 0.25, 0.5, 1.0, 2.0)

HELP = ("space: pause/play   left/right: step   up/down: speed   "
        "F: next failing frame   L: loop on/off   Home: restart")


class Playback:
    """Which frame to show when: ``n_frames`` frames at ``fps``, looping or stopping at the end.

    Time ``t`` (seconds of motion) advances by ``dt * speed`` per :meth:`tick` unless paused;
    the shown frame is ``floor(t * fps)``. ``failing`` frames can be jumped to with F."""

    def __init__(self, n_frames: int, fps: float, *, loop: bool = True, speed: float = 1.0,
                 failing: Iterable[int] = ()):
        if n_frames < 1 or not fps > 0:
            raise ValueError("need at least one frame and a positive fps")
        self.n_frames, self.fps = int(n_frames), float(fps)
        self.loop, self.speed = bool(loop), float(speed)
        self.failing = sorted({int(f) for f in failing if 0 <= int(f) < n_frames})
        self.paused = False
        self.t = 0.0
        self._lock = threading.Lock()

    @property
    def duration(self) -> float:
        return self.n_frames / self.fps

    @property
    def frame(self) -> int:
        return min(int(self.t * self.fps + 1e-9), self.n_frames - 1)

    @property
    def finished(self) -> bool:
        """True once a non-looping playback has reached the last frame and stopped."""
        return not self.loop and self.paused and self.frame == self.n_frames - 1

    def tick(self, dt: float) -> int:
        """Advance by ``dt`` wall-clock seconds; returns the frame to show."""
        with self._lock:
            if not self.paused:
                self.t += max(0.0, dt) * self.speed
                if self.t >= self.duration:
                    if self.loop:
                        self.t %= self.duration
                    else:
                        self.t = (self.n_frames - 1) / self.fps
                        self.paused = True
            return self.frame

    def _seek(self, frame: int) -> None:
        if self.loop:
            frame %= self.n_frames
        self.t = min(max(frame, 0), self.n_frames - 1) / self.fps

    def toggle_pause(self) -> None:
        with self._lock:
            if self.paused and not self.loop and self.frame == self.n_frames - 1:
                self.t = 0.0  # play again from the start
            self.paused = not self.paused

    def step(self, frames: int) -> None:
        """Pause and move by ``frames`` (wraps around when looping)."""
        with self._lock:
            self.paused = True
            self._seek(self.frame + frames)

    def restart(self) -> None:
        with self._lock:
            self.t = 0.0

    def next_failing(self) -> int | None:
        """Pause on the next failing frame after the current one (wrapping); None if there are none."""
        with self._lock:
            if not self.failing:
                return None
            later = [f for f in self.failing if f > self.frame]
            target = later[0] if later else self.failing[0]
            self.paused = True
            self._seek(target)
            return target

    def change_speed(self, up: bool) -> float:
        with self._lock:
            i = min(range(len(SPEEDS)), key=lambda k: abs(SPEEDS[k] - self.speed))
            self.speed = SPEEDS[min(i + 1, len(SPEEDS) - 1) if up else max(i - 1, 0)]
            return self.speed

    def on_key(self, key: int) -> None:
        """The viewer's ``key_callback``: GLFW key code -> action (other keys are ignored)."""
        if key == KEY_SPACE:
            self.toggle_pause()
        elif key == KEY_RIGHT:
            self.step(1)
        elif key == KEY_LEFT:
            self.step(-1)
        elif key == KEY_UP:
            self.change_speed(True)
        elif key == KEY_DOWN:
            self.change_speed(False)
        elif key == KEY_HOME:
            self.restart()
        elif key == KEY_F:
            self.next_failing()
        elif key == KEY_L:
            with self._lock:
                self.loop = not self.loop

    def status(self) -> str:
        state = "paused" if self.paused else f"x{self.speed:g}"
        return f"{state}{'  loop' if self.loop else ''}"

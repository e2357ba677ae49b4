"""The bundled op3 and demo clip, loaded once per test process (no ../shared needed)."""

from __future__ import annotations

import functools

from motion2robot.cli.cmd_demo import demo_motion_path
from motion2robot.motion import HumanMotion, read_motion


@functools.lru_cache(maxsize=1)
def op3():
    from motion2robot.robot import load_robot

    return load_robot("op3")


@functools.lru_cache(maxsize=4)
def demo_clip(frames: int) -> HumanMotion:
    """The bundled demo motion's first ``frames`` frames."""
    human = read_motion(demo_motion_path())[0]
    return human.with_(positions=human.positions[:frames],
                       contacts=None if human.contacts is None else human.contacts[:frames])

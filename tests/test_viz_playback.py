"""The viewer's playback state machine (no window needed)."""

from __future__ import annotations

import threading

import pytest

from motion2robot.viz.playback import (KEY_DOWN, KEY_F, KEY_HOME, KEY_L, KEY_LEFT, KEY_RIGHT, KEY_SPACE, KEY_UP,
                                       Playback)


def test_real_time_frames_follow_the_clock():
    pb = Playback(50, 20.0)
    assert pb.frame == 0
    assert pb.tick(0.049) == 0
    assert pb.tick(0.002) == 1  # 0.051 s -> frame 1 at 20 fps
    assert pb.tick(1.0) == 21
    pb.speed = 0.5
    assert pb.tick(1.0) == 31


def test_loop_wraps_and_once_stops_at_the_end():
    pb = Playback(10, 10.0, loop=True)
    assert pb.tick(1.25) == 2  # 1.25 s into a 1 s clip
    assert not pb.paused
    once = Playback(10, 10.0, loop=False)
    assert once.tick(5.0) == 9
    assert once.paused and once.finished
    once.toggle_pause()  # play again from the start
    assert not once.paused and once.frame == 0


def test_pause_freezes_time_and_steps_move_one_frame():
    pb = Playback(10, 10.0)
    pb.tick(0.35)
    pb.on_key(KEY_SPACE)
    assert pb.paused
    assert pb.tick(2.0) == 3
    pb.on_key(KEY_RIGHT)
    assert pb.frame == 4
    pb.on_key(KEY_LEFT)
    pb.on_key(KEY_LEFT)
    assert pb.frame == 2
    pb.on_key(KEY_SPACE)
    assert not pb.paused and pb.tick(0.1) == 3


def test_step_wraps_when_looping_and_clamps_otherwise():
    pb = Playback(5, 10.0, loop=True)
    pb.step(-1)
    assert pb.frame == 4 and pb.paused
    pb.step(1)
    assert pb.frame == 0
    once = Playback(5, 10.0, loop=False)
    once.step(-3)
    assert once.frame == 0
    once.step(99)
    assert once.frame == 4


def test_jump_to_failing_frames_cycles_through_them():
    pb = Playback(100, 20.0, failing=[40, 10, 70, 500])
    assert pb.failing == [10, 40, 70]  # out-of-range frames dropped, sorted
    assert pb.next_failing() == 10
    pb.on_key(KEY_F)
    assert pb.frame == 40 and pb.paused
    pb.on_key(KEY_F)
    pb.on_key(KEY_F)
    assert pb.frame == 10
    assert Playback(5, 10.0).next_failing() is None


def test_speed_loop_and_restart_keys():
    pb = Playback(100, 20.0)
    pb.on_key(KEY_UP)
    assert pb.speed == 2.0
    pb.on_key(KEY_DOWN)
    pb.on_key(KEY_DOWN)
    assert pb.speed == 0.5
    pb.on_key(KEY_L)
    assert not pb.loop
    pb.tick(1.0)
    pb.on_key(KEY_HOME)
    assert pb.frame == 0
    pb.on_key(ord("Q"))  # unknown keys are ignored
    assert "x0.5" in pb.status()


def test_keys_from_another_thread_are_safe():
    pb = Playback(1000, 100.0)

    def press():
        for _ in range(500):
            pb.on_key(KEY_RIGHT)

    threads = [threading.Thread(target=press) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert pb.frame == 2000 % 1000


def test_rejects_empty_clips():
    with pytest.raises(ValueError):
        Playback(0, 20.0)


def test_the_caption_says_the_tempo_and_the_stance():
    """A motion made slower or on the stance alternative says so in the viewer's and the video's caption."""
    from motion2robot.robot import load_robot
    from motion2robot.validate import examples
    from motion2robot.viz.scene import make_playable

    op3 = load_robot("op3")
    m = examples.standing(op3).with_(meta={"source": "walk.bvh", "tempo": 1.6,
                                           "fallback": {"mode": "stance", "why": "x", "what": "y"}})
    title = make_playable(m, op3).title
    assert "walk.bvh" in title and "tempo x1.60" in title and "legs: stance" in title
    assert "stance" not in make_playable(examples.standing(op3), op3).title

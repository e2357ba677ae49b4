"""Corpus cases: outputs, robot motions handed to stream, stream/servos options, robot configs, batch."""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from tests.fuzz.corpus import J, STREAM, case, good_robot_npz, npy, npz, robot_npz, robot_toml, text

# -- retarget / check outputs and values -----------------------------------------------------
case("retarget: -o is a directory")(lambda d: ["retarget", str(npy(d, J)), "-o", str(d)])
case("retarget: -o under a file")(lambda d: ["retarget", str(npy(d, J)), "-o", str(text(d, "f", "x") / "o.npz")])
case("retarget: 3e38 in a HumanML3D file")(lambda d: ["retarget", str(npy(d, np.where(
    (np.arange(30)[:, None, None] == 7) & (np.arange(22)[None, :, None] == 20), 3e38, J))), "-o", str(d / "o.npz")])
case("retarget: 1e20 wrist")(lambda d: ["retarget", str(npy(d, np.where(
    (np.arange(30)[:, None, None] == 9) & (np.arange(22)[None, :, None] == 21), 1e20, J))), "-o", str(d / "o.npz")])
case("retarget: FIFO")(lambda d: (os.mkfifo(d / "f.npy"), ["retarget", str(d / "f.npy"), "-o", str(d / "o.npz")])[1])
case("check: FIFO")(lambda d: (os.mkfifo(d / "f.npy"), ["check", str(d / "f.npy"), "--no-physics"])[1])
case("stream: FIFO")(lambda d: (os.mkfifo(d / "f.npz"), ["stream", str(d / "f.npz"), "--dry-run"])[1])
case("stream: /dev/zero")(lambda d: ["stream", "/dev/zero", "--dry-run", "--telemetry", str(d / "t.jsonl")])
case("retarget: unknown robot")(lambda d: ["retarget", str(npy(d, J)), "--robot", "r2d2"])
case("retarget: --iterations 0")(lambda d: ["retarget", str(npy(d, J)), "--iterations", "0"])
case("retarget: --source-fps nan")(lambda d: ["retarget", str(npy(d, J)), "--source-fps", "nan"])
case("check: --json is a directory")(lambda d: ["check", str(good_robot_npz(d)), "--no-physics", "--json", str(d)])
case("check: --html is a directory")(lambda d: ["check", str(good_robot_npz(d)), "--no-physics", "--html", str(d)])
for _v in ("nan", "0", "-20", "inf"):
    case(f"retarget: --fps {_v}")(lambda d, v=_v: ["retarget", str(npy(d, J)), "--fps", v, "-o", str(d / "o.npz")])
for _opt, _v in (("--slip-speed", "nan"), ("--touch-height", "-1"), ("--swing-clearance", "inf"), ("--stream-rate", "0")):
    case(f"check: {_opt} {_v}")(lambda d, o=_opt, v=_v: ["check", str(good_robot_npz(d)), "--no-physics", o, v])
for _opt, _v in (("--blend", "nan"), ("--blend", "-1"), ("--tolerance", "-1"), ("--tolerance", "inf")):
    case(f"edit: {_opt} {_v}")(lambda d, o=_opt, v=_v: ["edit", str(npy(d, J)), str(npy(d, J, "e.npy")), o, v])
for _opt, _v in (("--video-fps", "nan"), ("--video-fps", "0"), ("--speed", "0")):
    case(f"sim: {_opt} {_v}")(lambda d, o=_opt, v=_v: ["sim", str(good_robot_npz(d)), "--render", str(d / "o.gif"), o, v])
for _v in ("nan", "0", "-5"):
    case(f"demo: --rate {_v}")(lambda d, v=_v: ["demo", "--rate", v])
case("check: robot motion fps 0")(lambda d: ["check", str(robot_npz(d, fps=0.0)), "--no-physics"])
case("check: robot motion NaN qpos")(lambda d: ["check", str(robot_npz(d, qpos=np.full((20, 27), np.nan))), "--no-physics"])

# -- robot motion files handed to stream -----------------------------------------------------
for _label, _fps in (("0", 0.0), ("NaN", np.nan), ("inf", np.inf), ("negative", -50.0), ("text", "fast")):
    case(f"stream: motion fps {_label}")(lambda d, f=_fps: ["stream", str(robot_npz(d, fps=f)), *STREAM, str(d / "t.jsonl")])
case("stream: motion with 0 frames")(lambda d: ["stream", str(robot_npz(d, frames=0)), *STREAM, str(d / "t.jsonl")])
case("stream: motion qpos NaN")(lambda d: ["stream", str(robot_npz(d, qpos=np.full((20, 27), np.nan))), *STREAM,
                                           str(d / "t.jsonl")])
case("stream: motion qpos wrong width")(lambda d: ["stream", str(robot_npz(d, qpos=np.zeros((20, 5)))), *STREAM,
                                                   str(d / "t.jsonl")])
case("stream: motion of an unknown robot")(lambda d: ["stream", str(robot_npz(d, robot="r2d2")), *STREAM,
                                                      str(d / "t.jsonl")])
case("stream: motion meta not JSON")(lambda d: ["stream", str(robot_npz(d, meta="{")), *STREAM, str(d / "t.jsonl")])
case("stream: human motion")(lambda d: ["stream", str(npy(d, J)), *STREAM, str(d / "t.jsonl")])
case("stream: robot motion whose qpos expands to 528 MB")(lambda d: ["stream", str(_qpos_bomb(d)), *STREAM,
                                                                      str(d / "t.jsonl")])
case("stream: npz without qpos")(lambda d: ["stream", str(npz(d, joints=J, fps=20.0)), *STREAM, str(d / "t.jsonl")])
case("stream: missing file")(lambda d: ["stream", str(d / "none.npz"), *STREAM, str(d / "t.jsonl")])
case("stream: no target")(lambda d: ["stream", str(good_robot_npz(d))])
case("stream: --telemetry is a directory")(lambda d: ["stream", str(good_robot_npz(d)), "--dry-run", "--telemetry", str(d)])


def _qpos_bomb(d: Path) -> Path:
    from tests.fuzz.cases_files import _bomb

    return _bomb(d, "qpos", (4_888_889, 27))  # 528 MB of float32


def _stream_opt(*opts: str) -> Callable[[Path], list[str]]:
    return lambda d: ["stream", str(good_robot_npz(d)), *STREAM, str(d / "t.jsonl"), *opts]


for _opt, _values in (("--rate", ("0", "-1", "nan", "inf", "abc", "1e6")), ("--ramp-speed", ("0", "abc", "inf", "-1")),
                      ("--duration", ("-1", "nan", "x")), ("--watchdog-ms", ("-20", "5000", "1.5", "x")),
                      ("--max-divergence", ("0", "nan", "7")), ("--latency-ms", ("-1", "nan")),
                      ("--baud", ("abc", "0")), ("--on-end", ("hold:abc", "hold:nan", "hold:99")),
                      ("--on-fault", ("sometimes",)), ("--rest", ("sideways",))):
    for _v in _values:
        case(f"stream: {_opt} {_v}")(_stream_opt(_opt, _v))
for _pol in ("ramp_speed=abc", "watchdog_ms=x", "on_end=hold:nan", "on_end=hold:inf", "bogus=1", "on_end",
             "ramp_speed=inf", "watchdog_ms=1e9"):
    case(f"stream: --policy {_pol}")(_stream_opt("--policy", _pol))
case("stream: --policy TOML broken")(lambda d: _stream_opt("--policy", str(text(d, "p.toml", "on_end = = 1")))(d))
case("stream: --policy TOML ramp_speed text")(lambda d: _stream_opt("--policy", str(text(d, "p.toml", 'ramp_speed = "x"\n')))(d))
case("stream: --calibration missing")(_stream_opt("--calibration", "/nonexistent/c.json"))
case("stream: --calibration not JSON")(lambda d: _stream_opt("--calibration", str(text(d, "c.json", "{")))(d))
case("stream: --calibration offsets text")(lambda d: _stream_opt("--calibration", str(text(d, "c.json", json.dumps(
    {"robot": "op3", "offsets": {"r_knee": "x"}}))))(d))
case("stream: --rate 5 --watchdog-ms 100 (virtual)")(lambda d: ["stream", str(good_robot_npz(d)), "--virtual", "--rate",
                                                                "5", "--watchdog-ms", "100", "--telemetry", str(d / "t.jsonl")])
case("stream: --rate 0.1 (virtual, too slow for a watchdog)")(lambda d: ["stream", str(good_robot_npz(d)), "--virtual",
                                                                         "--rate", "0.1", "--telemetry", str(d / "t.jsonl")])

# -- servos ----------------------------------------------------------------------------------
case("servos: reboot --id 300")(lambda d: ["servos", "reboot", "--virtual", "--id", "300"])
case("servos: reboot --id abc")(lambda d: ["servos", "reboot", "--virtual", "--id", "abc"])
case("servos: write --value abc")(lambda d: ["servos", "write", "--virtual", "--register", "led", "--value", "abc"])
case("servos: write unknown register")(lambda d: ["servos", "write", "--virtual", "--register", "bogus", "--value", "1"])
case("servos: scan --ids 1-x")(lambda d: ["servos", "scan", "--virtual", "--ids", "1-x"])
case("servos: scan --ids 999")(lambda d: ["servos", "scan", "--virtual", "--ids", "999"])
case("servos: --port missing device")(lambda d: ["servos", "scan", "--port", str(d / "ttyNONE")])
case("servos: calibrate -o a directory")(lambda d: ["servos", "calibrate", "--virtual", "-o", str(d)])


# -- robot configs ---------------------------------------------------------------------------
def _robot_case(name: str, edit: Callable[[str], str], command: str = "stream") -> None:
    def build(d: Path) -> list[str]:
        toml = robot_toml(d, edit)
        if command == "show":
            return ["robots", "show", str(toml)]
        return ["stream", str(good_robot_npz(d)), "--robot", str(toml), *STREAM, str(d / "t.jsonl")]
    case(f"robot config: {name}")(build)


_robot_case("ticks_per_rev 0", lambda s: s.replace("ticks_per_rev = 4096", "ticks_per_rev = 0"))
_robot_case("ticks_per_rev negative", lambda s: s.replace("ticks_per_rev = 4096", "ticks_per_rev = -4096"))
_robot_case("ticks_per_rev text", lambda s: s.replace("ticks_per_rev = 4096", 'ticks_per_rev = "many"'))
_robot_case("unknown servo model", lambda s: s.replace('model = "XM430-W350"', 'model = "XM9000"'))
_robot_case("baud as text", lambda s: s.replace("baud = 2000000", 'baud = "fast"'))
_robot_case("baud negative", lambda s: s.replace("baud = 2000000", "baud = -1"))
_robot_case("servo for a joint that does not exist", lambda s: s.replace("r_sho_pitch = 1", "r_tail = 1"))
_robot_case("servo ID 300", lambda s: s.replace("r_sho_pitch = 1", "r_sho_pitch = 300"))
_robot_case("servo ID text", lambda s: s.replace("r_sho_pitch = 1", 'r_sho_pitch = "one"'))
_robot_case("duplicate servo IDs", lambda s: s.replace("l_sho_pitch = 2", "l_sho_pitch = 1"))
_robot_case("center text", lambda s: s.replace("center = 2048", 'center = "middle"'))
_robot_case("TOML syntax error", lambda s: s.replace("[servos]", "[servos"), "show")
_robot_case("missing MJCF", lambda s: s.replace("op3.xml", "nothing.xml"), "show")
_robot_case("default velocity negative", lambda s: s.replace("velocity = 4.8", "velocity = -4.8"), "show")
_robot_case("default velocity nan", lambda s: s.replace("velocity = 4.8", "velocity = nan"), "show")
_robot_case("default kp text", lambda s: s.replace("kp = 21.1", 'kp = "stiff"'), "show")
_robot_case("torque inf", lambda s: s.replace("torque = 4.1", "torque = inf"), "show")
case("robot config: not a file")(lambda d: ["robots", "show", str(d / "none.toml")])
case("robot config: an empty file")(lambda d: ["robots", "show", str(text(d, "e.toml", ""))])

# -- batch -----------------------------------------------------------------------------------
case("batch: --out is a directory")(lambda d: ["batch", str(npy(d, J)), "--robot", "op3", "--out", str(d)])
case("batch: missing input")(lambda d: ["batch", str(d / "none"), "--robot", "op3", "--out", str(d / "r.jsonl")])
case("batch: --jobs 0")(lambda d: ["batch", str(npy(d, J)), "--robot", "op3", "--out", str(d / "r.jsonl"), "--jobs", "0"])
case("batch: --jobs abc")(lambda d: ["batch", str(npy(d, J)), "--robot", "op3", "--out", str(d / "r.jsonl"), "--jobs", "x"])
case("batch: --max-tasks-per-child 0")(lambda d: ["batch", str(npy(d, J)), "--robot", "op3", "--out", str(d / "r.jsonl"),
                                                 "--max-tasks-per-child", "0"])
case("batch-report: --top -1")(lambda d: ["batch-report", str(text(d, "r.jsonl", "{}\n")), "--top", "-1"])
case("batch-report: not JSON lines")(lambda d: ["batch-report", str(text(d, "r.jsonl", "{{{\nnot json\n"))])
case("batch-report: missing file")(lambda d: ["batch-report", str(d / "none.jsonl")])

"""Robot TOML parsing: shape errors are one line and name the key; a good config parses fully."""

import pytest

from motion2robot.errors import RobotConfigError
from motion2robot.robot.config import parse_config

GOOD = {
    "name": "t",
    "model": {"mjcf": "t.xml", "root_body": "base"},
    "defaults": {"velocity": 5.0, "torque": 3.0, "kp": 10.0},
    "joints": {"k": {"range": [-1.0, 0.0], "reason": "one way"}},
    "nominal": {"k": -0.2},
    "keypoints": {"pelvis": "base", "left_wrist": {"body": "arm", "offset": [0, 0.1, 0]}, "head": {"site": "top"}},
    "feet": {s: {"body": f"{s}_foot", "sole_center": [0, 0, -0.03], "sole_half": [0.05, 0.03]} for s in ("left", "right")},
    "servos": {"ids": {"k": 3}, "sign": {"k": -1}},
}


def test_good_config_parses():
    c = parse_config(GOOD)
    assert c.joint("k").range == (-1.0, 0.0) and c.joint("k").velocity == 5.0
    assert c.joint("other").range is None and c.joint("other").torque == 3.0
    assert c.keypoint("left_wrist").offset == (0, 0.1, 0) and c.keypoint("head").site == "top"
    assert c.servos.by_joint()["k"].sign == -1 and c.servos.center == 2048
    corners = c.feet[0].corners()
    assert len(corners) == 4 and {x for x, _, _ in corners} == {0.05, -0.05}


def _with(**changes):
    import copy

    d = copy.deepcopy(GOOD)
    for path, value in changes.items():
        keys = path.split("__")
        t = d
        for k in keys[:-1]:
            t = t[k]
        if value is None:
            del t[keys[-1]]
        else:
            t[keys[-1]] = value
    return d


@pytest.mark.parametrize("changes, needle", [
    ({"bogus": 1}, "unknown key(s) bogus"),
    ({"joints__k__range": [0.5, 0.1]}, "lower < upper"),
    ({"joints__k__speed": 3}, "unknown key(s) speed in [joints.k]"),
    ({"keypoints__nose": "base"}, "not an SMPL keypoint"),
    ({"feet__left": None}, "missing [feet.left]"),
    ({"model__menagerie": "x"}, "exactly one of 'mjcf'"),
    ({"defaults__velocity": -1}, "must be positive"),
    ({"servos__ids__j2": 3}, "servo ID 3 is used by both"),
    ({"keypoints__head": {"site": "top", "offset": [0, 0, 0]}}, "'offset' goes with 'body'"),
])
def test_bad_configs(changes, needle):
    with pytest.raises(RobotConfigError) as e:
        parse_config(_with(**changes))
    assert needle in str(e.value) and "\n" not in str(e.value)

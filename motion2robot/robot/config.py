"""Robot configuration: the TOML beside a robot's MJCF, parsed into a frozen dataclass.

Schema (every length in metres, angle in radians, speed in rad/s, torque in N*m; body frames are
the MJCF's)::

    name = "op3"
    description = "ROBOTIS OP3, 20 x Dynamixel XM430-W350"

    [model]
    mjcf = "op3.xml"              # MJCF path relative to this TOML, or
    # menagerie = "unitree_g1"    # a MuJoCo Menagerie robot and its entry point
    # entry = "g1"
    root_body = "body_link"        # the floating base
    torso_body = "body_link"       # used for heading/tilt (may equal root_body)

    [defaults]                      # applied to joints that do not say otherwise
    velocity = 4.8
    torque = 4.1
    kp = 21.1                       # position-servo gain for physics playback (N*m/rad)

    [joints.l_knee]                 # one table per hinge; range may be omitted when the model
    range = [-2.3, 0.0]             # declares one (it must lie inside the model's range)
    velocity = 4.8                  # optional
    torque = 4.1                    # optional
    reason = "knee bends backwards only; shells touch at 2.3 rad"

    [nominal]                       # nominal standing posture, joint -> rad (others 0)
    l_knee = -0.6

    [keypoints]                     # SMPL22 keypoint -> robot body (+ offset in the body frame)
    pelvis = { body = "body_link", offset = [0.0, 0.0, 0.0] }
    left_wrist = { body = "l_el_link", offset = [-0.019, 0.145, 0.0], weight = 1.0 }
    head = { site = "head_top" }    # or an MJCF site

    [feet.left]                     # sole rectangle in the foot body's frame
    body = "l_ank_roll_link"
    sole_center = [0.024, 0.013, -0.0305]   # centre of the sole's bottom face
    sole_half = [0.0635, 0.039]             # half length (body x) and half width (body y)
    # sole_quat = [1, 0, 0, 0]              # optional: the sole's frame in the body frame (wxyz),
                                            # for feet whose body axes are not along the sole

    [scale]                         # optional overrides of the automatic human->robot scale
    legs = 0.45
    arms = 0.40

    [servos]                        # optional; see motion2robot.robot.servo_map

The config is validated against the compiled model in :mod:`motion2robot.robot.loader`
(bodies exist, ranges inside the model's); this module only checks the file's own shape.
"""

from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from motion2robot.errors import RobotConfigError
from motion2robot.motion.human import SMPL22
from motion2robot.hardware.control_table import TABLES
from motion2robot.robot.servo_map import ServoMap, ServoSpec

_TOP_KEYS = {"name", "description", "model", "defaults", "joints", "nominal", "keypoints", "feet", "scale", "servos"}
_MODEL_KEYS = {"mjcf", "menagerie", "entry", "root_body", "torso_body"}
_DEFAULT_KEYS = {"velocity", "torque", "kp"}
_JOINT_KEYS = {"range", "velocity", "torque", "reason", "kp"}
_KP_KEYS = {"body", "site", "offset", "weight"}
_FOOT_KEYS = {"body", "sole_center", "sole_half", "sole_quat"}
_SCALE_KEYS = {"legs", "arms", "height"}
_SERVO_KEYS = {"model", "baud", "ticks_per_rev", "center", "ids", "sign", "offset"}


@dataclass(frozen=True)
class JointConfig:
    """Per-hinge settings; ``range`` None means 'take the model's declared range'."""

    name: str
    range: tuple[float, float] | None
    velocity: float
    torque: float
    kp: float
    reason: str = ""


@dataclass(frozen=True)
class KeypointConfig:
    """A human keypoint tracked at ``offset`` (m) in robot body ``body``'s frame, or at MJCF site
    ``site`` (the loader resolves a site to its body and offset)."""

    human: str
    body: str | None
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    weight: float = 1.0
    site: str | None = None


@dataclass(frozen=True)
class FootConfig:
    """A foot: its body and the sole rectangle (centre of the bottom face, half extents) in that body's frame."""

    side: str
    body: str
    sole_center: tuple[float, float, float]
    sole_half: tuple[float, float]
    sole_quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)  # sole frame in the body frame (wxyz)

    def corners(self) -> tuple[tuple[float, float, float], ...]:
        """The four sole corners in the foot body's frame (front-left, front-right, back-right,
        back-left): the rectangle lies in the x/y plane of the sole frame (``sole_quat``, the
        body's own frame unless the config says otherwise), centred on ``sole_center``."""
        w, x, y, z = self.sole_quat
        rot = ((1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
               (2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
               (2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)))
        hx, hy = self.sole_half
        out = []
        for sx, sy in ((1, 1), (1, -1), (-1, -1), (-1, 1)):
            u, v = sx * hx, sy * hy
            out.append(tuple(c + r[0] * u + r[1] * v for c, r in zip(self.sole_center, rot)))
        return tuple(out)


@dataclass(frozen=True)
class RobotConfig:
    """A robot's configuration as read from its TOML (not yet checked against the model)."""

    name: str
    description: str
    path: Path | None
    mjcf: Path | None
    menagerie: str | None
    entry: str | None
    root_body: str
    torso_body: str
    default_velocity: float
    default_torque: float
    default_kp: float
    joints: Mapping[str, JointConfig]
    nominal: Mapping[str, float]
    keypoints: tuple[KeypointConfig, ...]
    feet: tuple[FootConfig, FootConfig]
    scale: Mapping[str, float] = field(default_factory=dict)
    servos: ServoMap | None = None

    def joint(self, name: str) -> JointConfig:
        """Settings for hinge ``name``, falling back to the defaults."""
        j = self.joints.get(name)
        if j is not None:
            return j
        return JointConfig(name, None, self.default_velocity, self.default_torque, self.default_kp)

    def keypoint(self, human: str) -> KeypointConfig | None:
        return next((k for k in self.keypoints if k.human == human), None)


def load_config(path: str | Path) -> RobotConfig:
    """Read and shape-check a robot TOML; errors are one-line :class:`RobotConfigError`."""
    path = Path(path)
    if not path.is_file():
        raise RobotConfigError(f"{path}: robot config not found; give a .toml beside the MJCF or draft one with 'motion2robot robots init MODEL.xml -o NAME.toml'")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise RobotConfigError(f"{path}: not valid TOML ({err}); fix the syntax") from err
    return parse_config(data, path)


def parse_config(data: Mapping[str, Any], path: Path | None = None) -> RobotConfig:
    """Build a :class:`RobotConfig` from parsed TOML data (``path`` anchors relative MJCF paths)."""
    where = str(path) if path else "robot config"

    def fail(msg: str) -> RobotConfigError:
        return RobotConfigError(f"{where}: {msg}")

    def check_keys(table: Mapping[str, Any], allowed: set[str], name: str) -> None:
        if not isinstance(table, Mapping):
            raise fail(f"[{name}] must be a table")
        unknown = sorted(set(table) - allowed)
        if unknown:
            raise fail(f"unknown key(s) {', '.join(unknown)} in [{name}]; allowed: {', '.join(sorted(allowed))}")

    def num(value: Any, name: str, positive: bool = False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise fail(f"{name} must be a finite number, got {value!r}")
        if positive and value <= 0:
            raise fail(f"{name} must be positive, got {value!r}")
        return float(value)

    def vec(value: Any, n: int, name: str) -> tuple[float, ...]:
        if not isinstance(value, (list, tuple)) or len(value) != n:
            raise fail(f"{name} must be a list of {n} numbers, got {value!r}")
        return tuple(num(v, name) for v in value)

    check_keys(data, _TOP_KEYS, "top level")
    if "name" not in data:
        raise fail("missing 'name'")
    model = data.get("model", {})
    check_keys(model, _MODEL_KEYS, "model")
    if bool(model.get("mjcf")) == bool(model.get("menagerie")):
        raise fail("[model] needs exactly one of 'mjcf' (a path) or 'menagerie' (a Menagerie robot name)")
    for key in ("root_body",):
        if key not in model:
            raise fail(f"[model] is missing '{key}'")
    mjcf = None
    if model.get("mjcf"):
        mjcf = Path(model["mjcf"])
        if path is not None and not mjcf.is_absolute():
            mjcf = Path(os.path.abspath(path.parent / mjcf))  # absolute: robust to later chdir, readable in listings

    defaults = data.get("defaults", {})
    check_keys(defaults, _DEFAULT_KEYS, "defaults")
    dv = num(defaults.get("velocity", 4.8), "defaults.velocity", positive=True)
    dt = num(defaults.get("torque", 4.1), "defaults.torque", positive=True)
    dk = num(defaults.get("kp", 20.0), "defaults.kp", positive=True)

    joints: dict[str, JointConfig] = {}
    for jname, jt in data.get("joints", {}).items():
        check_keys(jt, _JOINT_KEYS, f"joints.{jname}")
        rng = None
        if "range" in jt:
            lo, hi = vec(jt["range"], 2, f"joints.{jname}.range")
            if not lo < hi:
                raise fail(f"joints.{jname}.range must be [lower, upper] with lower < upper, got {jt['range']}")
            rng = (lo, hi)
        joints[jname] = JointConfig(
            name=jname, range=rng,
            velocity=num(jt.get("velocity", dv), f"joints.{jname}.velocity", positive=True),
            torque=num(jt.get("torque", dt), f"joints.{jname}.torque", positive=True),
            kp=num(jt.get("kp", dk), f"joints.{jname}.kp", positive=True),
            reason=str(jt.get("reason", "")),
        )

    nominal = {k: num(v, f"nominal.{k}") for k, v in data.get("nominal", {}).items()}

    keypoints = []
    for human, kt in data.get("keypoints", {}).items():
        if human not in SMPL22:
            raise fail(f"keypoints.{human} is not an SMPL keypoint; use one of {', '.join(SMPL22)}")
        if isinstance(kt, str):
            kt = {"body": kt}
        check_keys(kt, _KP_KEYS, f"keypoints.{human}")
        if ("body" in kt) == ("site" in kt):
            raise fail(f"keypoints.{human} needs exactly one of 'body' (+ optional 'offset') or 'site'")
        if "site" in kt and "offset" in kt:
            raise fail(f"keypoints.{human}: 'offset' goes with 'body', not with 'site'")
        keypoints.append(KeypointConfig(
            human=human, body=str(kt["body"]) if "body" in kt else None,
            site=str(kt["site"]) if "site" in kt else None,
            offset=vec(kt.get("offset", [0.0, 0.0, 0.0]), 3, f"keypoints.{human}.offset"),
            weight=num(kt.get("weight", 1.0), f"keypoints.{human}.weight", positive=True),
        ))
    if not keypoints:
        raise fail("no [keypoints]: map at least pelvis, hips, knees, ankles, shoulders, elbows and wrists to robot bodies")

    feet_t = data.get("feet", {})
    feet = []
    for side in ("left", "right"):
        if side not in feet_t:
            raise fail(f"missing [feet.{side}] (foot body and sole rectangle); the retargeter and the balance check need both feet")
        ft = feet_t[side]
        check_keys(ft, _FOOT_KEYS, f"feet.{side}")
        for key in _FOOT_KEYS - {"sole_quat"}:
            if key not in ft:
                raise fail(f"[feet.{side}] is missing '{key}'")
        half = vec(ft["sole_half"], 2, f"feet.{side}.sole_half")
        if min(half) <= 0:
            raise fail(f"feet.{side}.sole_half must be positive")
        quat = vec(ft.get("sole_quat", [1.0, 0.0, 0.0, 0.0]), 4, f"feet.{side}.sole_quat")
        norm = math.sqrt(sum(q * q for q in quat))
        if norm < 1e-6:
            raise fail(f"feet.{side}.sole_quat must be a rotation quaternion (w, x, y, z), not zero")
        feet.append(FootConfig(side, str(ft["body"]), vec(ft["sole_center"], 3, f"feet.{side}.sole_center"), half,
                               tuple(q / norm for q in quat)))

    scale = data.get("scale", {})
    check_keys(scale, _SCALE_KEYS, "scale")
    scale = {k: num(v, f"scale.{k}", positive=True) for k, v in scale.items()}

    servos = None
    if "servos" in data:
        st = data["servos"]
        check_keys(st, _SERVO_KEYS, "servos")
        ids = st.get("ids", {})
        if not ids:
            raise fail("[servos] needs [servos.ids] (joint -> Dynamixel ID)")
        seen: dict[int, str] = {}
        specs = []
        for jname, sid in ids.items():
            if isinstance(sid, bool) or not isinstance(sid, int) or not 0 <= sid <= 252:
                raise fail(f"servos.ids.{jname} must be an integer ID 0..252, got {sid!r}")
            if sid in seen:
                raise fail(f"servo ID {sid} is used by both {seen[sid]} and {jname}")
            seen[sid] = jname
            sign = st.get("sign", {}).get(jname, 1)
            if sign not in (1, -1):
                raise fail(f"servos.sign.{jname} must be 1 or -1")
            off = st.get("offset", {}).get(jname, 0)
            if isinstance(off, bool) or not isinstance(off, int):
                raise fail(f"servos.offset.{jname} must be an integer number of ticks")
            specs.append(ServoSpec(jname, sid, sign, off))
        def whole(key: str, default: int, low: int, high: int, unit: str) -> int:
            v = st.get(key, default)
            if isinstance(v, bool) or not isinstance(v, int) or not low <= v <= high:
                raise fail(f"servos.{key} must be a whole number of {unit} in {low}..{high}, got {v!r}")
            return v

        model_name = st.get("model", "XM430-W350")
        if model_name not in TABLES:
            raise fail(f"servos.model {model_name!r} has no control table; use one of {', '.join(TABLES)}")
        ticks = whole("ticks_per_rev", 4096, 1, 1 << 20, "ticks")
        servos = ServoMap(
            model=model_name, baud=whole("baud", 2_000_000, 9600, 10_500_000, "bit/s"),
            ticks_per_rev=ticks, center=whole("center", 2048, -(1 << 31), (1 << 31) - 1, "ticks"),
            servos=tuple(specs),
        )

    return RobotConfig(
        name=str(data["name"]), description=str(data.get("description", "")), path=path,
        mjcf=mjcf, menagerie=model.get("menagerie"), entry=model.get("entry"),
        root_body=str(model["root_body"]), torso_body=str(model.get("torso_body", model["root_body"])),
        default_velocity=dv, default_torque=dt, default_kp=dk,
        joints=MappingProxyType(joints), nominal=MappingProxyType(nominal),
        keypoints=tuple(keypoints), feet=(feet[0], feet[1]),
        scale=MappingProxyType(scale), servos=servos,
    )

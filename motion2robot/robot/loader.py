"""Load a :class:`Robot`: resolve the name, read the TOML, edit the MJCF (ranges, sites), compile, validate."""

from __future__ import annotations

import functools
import hashlib
import re
from pathlib import Path

import mujoco
import numpy as np

from motion2robot.errors import RobotConfigError
from motion2robot.robot.config import RobotConfig, load_config
from motion2robot.robot.resolve import menagerie_mjcf, resolve
from motion2robot.robot.robot import Robot

_HINGE = mujoco.mjtJoint.mjJNT_HINGE
_FREE = mujoco.mjtJoint.mjJNT_FREE


def load_robot(name: str = "op3") -> Robot:
    """The robot called ``name`` (``op3`` | ``menagerie:NAME`` | path to MJCF or TOML), compiled and checked.

    Results are cached per process (a Robot is immutable); paths are keyed by their absolute
    location and modification time, so an edited config is reloaded."""
    key = str(name)
    p = Path(key).expanduser()
    if p.suffix.lower() in (".xml", ".toml") and p.is_file():
        key = f"{p.resolve()}@{p.stat().st_mtime_ns}"
        cfg = p.with_suffix(".toml")
        if cfg.is_file():
            key += f"@{cfg.stat().st_mtime_ns}"
        return _load_cached(key, str(p.resolve()))
    return _load_cached(key, key)


def _cache_clear() -> None:
    _load_cached.cache_clear()


load_robot.cache_clear = _cache_clear  # type: ignore[attr-defined]


@functools.lru_cache(maxsize=16)
def _load_cached(key: str, name: str) -> Robot:
    src = resolve(name)
    config = load_config(src.config_path)
    if src.mjcf_path is not None:
        mjcf, origin = src.mjcf_path, src.origin
    elif config.menagerie:
        mjcf, origin = menagerie_mjcf(config.menagerie, config.entry)
    else:
        mjcf, origin = config.mjcf, src.origin
    return build_robot(config, mjcf, name=src.name, source=origin)


def build_robot(config: RobotConfig, mjcf: str | Path, *, name: str | None = None, source: str = "") -> Robot:
    """Compile ``mjcf`` with ``config`` applied and check the config against the model."""
    mjcf = Path(mjcf)
    where = str(config.path or name or mjcf)
    if not mjcf.is_file():
        raise RobotConfigError(f"{where}: MJCF {mjcf} not found; fix [model] mjcf")
    try:
        spec = mujoco.MjSpec.from_file(str(mjcf))
    except Exception as err:
        raise mjcf_error(mjcf, err) from err

    bodies = {b.name: b for b in spec.bodies if b.name}
    _apply_joint_ranges(spec, config, where)
    for kp in config.keypoints:
        if kp.body is not None:
            if kp.body not in bodies:
                raise RobotConfigError(f"{where}: keypoints.{kp.human} names body {kp.body!r}, which the model does not have; use one of the model's bodies (see 'motion2robot robots show')")
            bodies[kp.body].add_site(name=f"kp_{kp.human}", pos=list(kp.offset), size=[0.005, 0, 0], group=5)
    for foot in config.feet:
        if foot.body not in bodies:
            raise RobotConfigError(f"{where}: feet.{foot.side}.body {foot.body!r} is not a body of the model; name the foot (ankle/sole) body")
        b = bodies[foot.body]
        for i, c in enumerate(foot.corners()):
            b.add_site(name=f"sole_{foot.side}_{i}", pos=list(c), size=[0.003, 0, 0], group=5)
        b.add_site(name=f"sole_{foot.side}_c", pos=list(foot.sole_center), size=[0.003, 0, 0], group=5)
    for key in ("root_body", "torso_body"):
        if getattr(config, key) not in bodies:
            raise RobotConfigError(f"{where}: [model] {key} {getattr(config, key)!r} is not a body of the model")
    try:
        model = spec.compile()
    except Exception as err:
        raise RobotConfigError(f"{where}: the model does not compile with this config ({' '.join(str(err).split())})") from err
    return _assemble(config, model, str(mjcf), name or config.name, source, where)


def mjcf_error(mjcf: Path, err: Exception) -> RobotConfigError:
    """One line for an MJCF MuJoCo cannot read: a missing or unreadable mesh/asset file is named
    with where it was looked for; anything else quotes MuJoCo."""
    text = " ".join(str(err).split())
    m = re.search(r"(?:Error opening file|resource not found via provider or OS filesystem:?) '?([^',]+)'?", text)
    if m:
        return RobotConfigError(
            f"{mjcf}: asset file '{m.group(1)}' cannot be read (looked for relative to {mjcf.parent} and the "
            "MJCF's compiler meshdir/assetdir/texturedir); fix that path in the MJCF or put the file there")
    return RobotConfigError(f"{mjcf}: MuJoCo cannot read this MJCF ({text}); fix the model file")


def _apply_joint_ranges(spec: mujoco.MjSpec, config: RobotConfig, where: str) -> None:
    names = {j.name for j in spec.joints}
    unknown = sorted(set(config.joints) - names)
    if unknown:
        raise RobotConfigError(f"{where}: [joints] names {', '.join(unknown)}, not joints of the model; check the names with 'motion2robot robots show'")
    bad_nominal = sorted(set(config.nominal) - names)
    if bad_nominal:
        raise RobotConfigError(f"{where}: [nominal] names {', '.join(bad_nominal)}, not joints of the model")
    hinges = [j.name for j in spec.joints if j.type == _HINGE]
    bad_servos = sorted({s.joint for s in config.servos.servos} - set(hinges)) if config.servos else []
    if bad_servos:
        more = ", ..." if len(hinges) > 8 else ""
        raise RobotConfigError(f"{where}: [servos.ids] names {', '.join(bad_servos)}, not hinge joints of the model; "
                               f"use the model's joint names ({', '.join(hinges[:8])}{more})")
    for j in spec.joints:
        if j.type != _HINGE:
            continue
        jc = config.joints.get(j.name)
        model_limited = j.limited == mujoco.mjtLimited.mjLIMITED_TRUE or (
            j.limited == mujoco.mjtLimited.mjLIMITED_AUTO and j.range[0] < j.range[1])
        if jc is not None and jc.range is not None:
            lo, hi = jc.range
            if model_limited and (lo < j.range[0] - 1e-9 or hi > j.range[1] + 1e-9):
                raise RobotConfigError(
                    f"{where}: joints.{j.name}.range [{lo:.4g}, {hi:.4g}] lies outside the model's range "
                    f"[{j.range[0]:.4g}, {j.range[1]:.4g}]; narrow it to the model's range")
            j.range = [lo, hi]
        elif not model_limited:
            raise RobotConfigError(f"{where}: joint {j.name} has no range in the model and none in the config; add [joints.{j.name}] range = [lower, upper] (rad)")
        j.limited = mujoco.mjtLimited.mjLIMITED_TRUE


def _assemble(config: RobotConfig, model: mujoco.MjModel, mjcf: str, name: str, source: str, where: str) -> Robot:
    if model.njnt == 0 or model.jnt_type[0] != _FREE or model.jnt_bodyid[0] != mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, config.root_body):
        raise RobotConfigError(f"{where}: the model's first joint must be a free joint on the root body {config.root_body!r}")
    other = [i for i in range(1, model.njnt) if model.jnt_type[i] != _HINGE]
    if other:
        raise RobotConfigError(f"{where}: only hinge joints are supported besides the free root; {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, other[0])} is not a hinge")
    jids = np.arange(1, model.njnt)
    names = tuple(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, int(i)) for i in jids)
    if not np.array_equal(model.jnt_qposadr[jids], 7 + np.arange(len(jids))):
        raise RobotConfigError(f"{where}: hinge qpos addresses are not contiguous after the root")
    lower, upper = model.jnt_range[jids, 0].copy(), model.jnt_range[jids, 1].copy()
    jc = [config.joint(n) for n in names]
    vel = np.array([j.velocity for j in jc])
    torque = np.array([j.torque for j in jc])
    kp = np.array([j.kp for j in jc])

    def site(nm: str) -> int:
        sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, nm)
        if sid < 0:
            raise RobotConfigError(f"{where}: site {nm!r} is not in the model; fix [keypoints]")
        return sid

    kps = tuple(k.human for k in config.keypoints)
    kp_sites = np.array([site(k.site if k.site else f"kp_{k.human}") for k in config.keypoints], dtype=np.int64)
    kp_w = np.array([k.weight for k in config.keypoints])
    sole = np.array([[site(f"sole_{s}_{i}") for i in range(4)] for s in ("left", "right")], dtype=np.int64)
    sole_c = np.array([site(f"sole_{s}_c") for s in ("left", "right")], dtype=np.int64)
    body = lambda nm: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, nm)  # noqa: E731
    feet = np.array([body(f.body) for f in config.feet], dtype=np.int64)

    q = np.zeros(model.nq)
    q[3] = 1.0
    for i, n in enumerate(names):
        v = config.nominal.get(n, 0.0)
        if not lower[i] - 1e-9 <= v <= upper[i] + 1e-9:
            raise RobotConfigError(f"{where}: nominal.{n} = {v:.4g} rad is outside the joint's range [{lower[i]:.4g}, {upper[i]:.4g}]")
        q[7 + i] = v
    data = mujoco.MjData(model)
    data.qpos[:] = q
    mujoco.mj_kinematics(model, data)
    q[2] = -float(data.site_xpos[sole.ravel(), 2].min())
    data.qpos[:] = q
    mujoco.mj_kinematics(model, data)
    height = float(data.site_xpos[kp_sites, 2].max())
    mujoco.mj_setConst(model, data)
    h = hashlib.sha256()
    for arr in (model.body_pos, model.body_quat, model.body_mass, model.jnt_axis, model.jnt_range, model.geom_size, model.site_pos):
        h.update(np.ascontiguousarray(arr, dtype=np.float64).tobytes())
    for a in (lower, upper, vel, torque, kp, q):
        a.flags.writeable = False
    return Robot(
        name=name, source=source, config=config, model=model, mjcf_path=mjcf, joint_names=names,
        joint_ids=jids, lower=lower, upper=upper, velocity_limit=vel, torque_limit=torque, kp=kp,
        nominal_qpos=q, keypoints=kps, keypoint_sites=kp_sites, keypoint_weights=kp_w,
        sole_sites=sole, sole_center_sites=sole_c, foot_bodies=feet,
        root_body=body(config.root_body), torso_body=body(config.torso_body),
        mass=float(model.body_subtreemass[0]), height=height, model_hash=h.hexdigest()[:16],
    )

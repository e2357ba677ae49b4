"""Draft a robot config for a humanoid MJCF motion2robot has never seen.

:func:`draft_config` walks the kinematic tree at the model's ``qpos0`` (world frame, z up):

* root: the body with the free joint; legs: the lowest leaf body on each side (y sign in the
  root frame) is the foot, its path from the root the leg; arms: on each side the leaf body
  farthest along the tree that is not in a leg; torso: the body where the two arms branch.
* knee / elbow: the body named so, else the chain body halfway down (flagged CHECK).
* hip / shoulder / ankle / wrist: the point where the joint group's hinge axes meet (least
  squares), attached to the chain body nearest to it. Without wrist joints the wrist is put near
  the tip of the forearm geometry (CHECK).
* head: a body, geom or mesh named ``head``, else the highest body (CHECK); neck and spine3 are
  put on the torso between shoulders and head / shoulders and hips.
* soles: the rectangle covering the foot's collision geometry within 5 mm of its lowest point.
* limits: ranges from the model (none declared: +-1.5 rad, CHECK); torque from the actuators'
  force range, the joint's actuatorfrcrange, or a motor's ctrlrange x gear; velocity is not in
  an MJCF (default, CHECK); kp from a position actuator's gain, else torque / 0.5 rad.
* nominal: zeros, with the knees bent 0.3 rad (hip and ankle pitch -0.15) when the pitch joints
  are found and the ranges allow it.

The draft is checked by loading it like any robot (:func:`~motion2robot.robot.loader.build_robot`);
what it could not settle is listed in ``Draft.checks`` and marked ``CHECK`` in the TOML.
"""

from __future__ import annotations

import os
import sys
from dataclasses import replace
from pathlib import Path

import mujoco

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from motion2robot.errors import RobotConfigError
from motion2robot.robot.config import parse_config
from motion2robot.robot.draft_toml import render
from motion2robot.robot.draft_tree import Skeleton
from motion2robot.robot.draft_types import Draft, FootDraft, JointDraft, KeypointDraft
from motion2robot.robot.loader import build_robot, mjcf_error
from motion2robot.robot.resolve import MENAGERIE_PREFIX, menagerie_mjcf

__all__ = ["Draft", "JointDraft", "KeypointDraft", "FootDraft", "draft_config", "write_draft"]


def draft_config(model: str | Path, name: str | None = None) -> Draft:
    """Draft a config for ``model`` (an MJCF path or ``menagerie:NAME``); raises
    :class:`RobotConfigError` when the model is not a humanoid it can read."""
    mjcf, menagerie, entry = _locate(str(model))
    try:
        m = mujoco.MjModel.from_xml_path(str(mjcf))
    except Exception as err:
        raise mjcf_error(mjcf, err) from err
    d = mujoco.MjData(m)
    d.qpos[:] = m.qpos0
    mujoco.mj_kinematics(m, d)
    tree = Skeleton(m, d, str(mjcf))
    draft = tree.draft(name or mjcf.stem, str(model), mjcf, menagerie, entry)
    return _verify(draft)


def write_draft(draft: Draft, path: str | Path) -> Path:
    """Write ``draft`` as TOML to ``path`` (an MJCF path is stored relative to the file)."""
    path = Path(path)
    ref = None if draft.menagerie else os.path.relpath(draft.mjcf.resolve(), path.resolve().parent)
    try:
        path.write_text(render(draft, ref), encoding="utf-8")
    except OSError as err:
        raise RobotConfigError(f"{path}: cannot write the draft ({err.strerror}); choose another -o path") from err
    return path


def _locate(model: str) -> tuple[Path, str | None, str | None]:
    if model.startswith(MENAGERIE_PREFIX):
        mname = model[len(MENAGERIE_PREFIX):]
        mjcf, _ = menagerie_mjcf(mname, None)
        return mjcf, mname, mjcf.stem
    p = Path(model).expanduser()
    if not p.is_file():
        raise RobotConfigError(f"{p}: MJCF not found; give a path to a humanoid MJCF (.xml) or menagerie:NAME")
    return p, None, None


def _verify(draft: Draft) -> Draft:
    """Load the draft like a user would; add CHECK notes for tilted soles and self-contacts."""
    text = render(draft, None)
    config = parse_config(tomllib.loads(text), None)
    robot = build_robot(config, draft.mjcf, name=draft.name)
    data = robot.new_data()
    mujoco.mj_forward(robot.model, data)
    checks = list(draft.checks)
    corners = data.site_xpos[robot.sole_sites.ravel(), 2]
    if corners.max() - corners.min() > 0.002:
        checks.append(f"soles are not flat at the nominal pose (corner heights differ by "
                      f"{1000 * (corners.max() - corners.min()):.1f} mm): fix [nominal] ankle angles or the sole rectangle")
    m = robot.model
    pairs = sorted({tuple(sorted((mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.geom_bodyid[c.geom1])),
                                  mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.geom_bodyid[c.geom2])))))
                    for c in data.contact[: data.ncon]})
    if pairs:
        checks.append("self-contact at the nominal pose between " + ", ".join(f"{a}/{b}" for a, b in pairs)
                      + ": adjust [nominal]")
    return replace(draft, checks=tuple(checks), height=robot.height)

"""A picture of a robot's keypoint map: the robot at its nominal pose on the floor, front and side
views, each keypoint a coloured ball labelled with its SMPL name, the sole rectangles outlined.

Left keypoints are blue, right ones red, the trunk's yellow; the soles are green. Offscreen
rendering (EGL or OSMesa, see :mod:`motion2robot.viz.gl`).
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from motion2robot.errors import UserError
from motion2robot.robot.robot import Robot
from motion2robot.robot.world import make_world
from motion2robot.viz.camera import fit_distance
from motion2robot.viz.render import OffscreenRenderer, side_by_side

LEFT_RGBA = np.array([0.15, 0.45, 1.0, 1.0], dtype=np.float32)
RIGHT_RGBA = np.array([1.0, 0.2, 0.15, 1.0], dtype=np.float32)
TRUNK_RGBA = np.array([1.0, 0.85, 0.1, 1.0], dtype=np.float32)
SOLE_RGBA = np.array([0.1, 0.85, 0.3, 1.0], dtype=np.float32)
#: Opacity the robot's geoms are drawn with.
GHOST = 0.35


def keypoint_colour(human: str) -> np.ndarray:
    return LEFT_RGBA if human.startswith("left_") else RIGHT_RGBA if human.startswith("right_") else TRUNK_RGBA


def _decorate(scene: mujoco.MjvScene, robot: Robot, data: mujoco.MjData, radius: float) -> None:
    eye = np.eye(3).ravel()
    for human, site in zip(robot.keypoints, robot.keypoint_sites):
        if scene.ngeom >= scene.maxgeom:
            return
        g = scene.geoms[scene.ngeom]
        mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_SPHERE, np.array([radius, 0, 0]), data.site_xpos[site], eye,
                            keypoint_colour(human))
        g.label = human
        scene.ngeom += 1
    for corners in robot.sole_sites:
        pts = data.site_xpos[corners]
        for a, b in zip(pts, np.roll(pts, -1, axis=0)):
            if scene.ngeom >= scene.maxgeom:
                return
            g = scene.geoms[scene.ngeom]
            mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_CAPSULE, np.zeros(3), np.zeros(3), eye, SOLE_RGBA)
            mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_CAPSULE, radius / 3, a, b)
            scene.ngeom += 1


def render_keypoints(robot: Robot, size: tuple[int, int] = (640, 720)) -> np.ndarray:
    """(H, 2W, 3) uint8 image: front and side views of ``robot`` at its nominal pose, keypoints marked."""
    model = make_world(robot)
    robot_geoms = model.geom_bodyid != 0
    model.geom_rgba[robot_geoms, 3] *= GHOST  # see-through, so the keypoints inside show
    model.mat_rgba[:, 3] *= GHOST
    data = mujoco.MjData(model)
    data.qpos[:] = robot.nominal_qpos
    mujoco.mj_forward(model, data)
    width, height = size
    top = max(robot.height, 0.1)
    radius = max(0.006, 0.012 * top)
    centre = np.array([robot.nominal_qpos[0], robot.nominal_qpos[1], top / 2])
    images = []
    with OffscreenRenderer(model, width, height) as r:
        r.option.label = int(mujoco.mjtLabel.mjLABEL_NONE)
        r.option.geomgroup[:] = 1
        r.option.geomgroup[3] = 0  # collision geoms of Menagerie models (group 3) hidden behind the visual ones
        if not any(model.geom_group[g] != 3 for g in range(model.ngeom) if model.geom_bodyid[g] != 0):
            r.option.geomgroup[3] = 1
        for azimuth in (180.0, 90.0):  # from the front, from the side
            r.camera.type = mujoco.mjtCamera.mjCAMERA_FREE
            r.camera.lookat[:] = centre
            r.camera.azimuth, r.camera.elevation = azimuth, -10.0
            r.camera.distance = fit_distance(0.6 * top, 0.6 * top, aspect=width / height)
            view = "front" if azimuth == 180.0 else "side"
            images.append(r.render(data, lambda scn: _decorate(scn, robot, data, radius),
                                   title=f"{robot.name}: keypoints ({view})"))
    return side_by_side(images)


def write_keypoint_image(robot: Robot, path: str | Path, size: tuple[int, int] = (640, 720)) -> Path:
    """Render :func:`render_keypoints` to a PNG (or JPEG) file; returns the path."""
    path = Path(path)
    if path.suffix.lower() not in (".png", ".jpg", ".jpeg"):
        raise UserError(f"{path}: --render writes a picture; use a .png or .jpg file name")
    from PIL import Image

    image = render_keypoints(robot, size)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(image).save(path)
    except OSError as err:
        raise UserError(f"{path}: cannot write the picture ({err.strerror or err}); choose another path") from err
    return path

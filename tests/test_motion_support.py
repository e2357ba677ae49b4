"""Synthetic motion sources for the motion tests (a standing/walking body in HumanML3D space
and a small BVH writer), plus checks that the synthetic data is what the tests assume."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2robot.motion.human import KP, SMPL22, SMPL22_PARENTS

# Rest pose, HumanML3D axes: y up, facing +z, subject's left at +x, metres.
REST_YUP = np.array([
    [0.0, 0.95, 0.0], [0.06, 0.86, 0.0], [-0.06, 0.86, 0.0], [0.0, 1.06, 0.0],
    [0.10, 0.48, 0.0], [-0.10, 0.48, 0.0], [0.0, 1.19, 0.0], [0.10, 0.08, 0.0],
    [-0.10, 0.08, 0.0], [0.0, 1.25, 0.0], [0.10, 0.02, 0.12], [-0.10, 0.02, 0.12],
    [0.0, 1.46, 0.0], [0.07, 1.38, 0.0], [-0.07, 1.38, 0.0], [0.0, 1.55, 0.03],
    [0.17, 1.40, 0.0], [-0.17, 1.40, 0.0], [0.42, 1.40, 0.0], [-0.42, 1.40, 0.0],
    [0.66, 1.40, 0.0], [-0.66, 1.40, 0.0],
])


def walking_yup(frames: int = 40, fps: float = 20.0, speed: float = 1.0, bob: float = 0.02) -> np.ndarray:
    """(T, 22, 3) y-up metres: the rest pose gliding along +z at ``speed`` m/s with a bob."""
    t = np.arange(frames) / fps
    pos = np.repeat(REST_YUP[None], frames, axis=0).copy()
    pos[..., 2] += speed * t[:, None]
    pos[:, [KP["pelvis"], KP["spine1"], KP["head"]], 1] += bob * np.sin(2 * np.pi * t)[:, None]
    return pos


# Mixamo-style names for a BVH with one joint per SMPL22 keypoint.
MIXAMO_NAMES = ("Hips", "LeftUpLeg", "RightUpLeg", "Spine", "LeftLeg", "RightLeg", "Spine1", "LeftFoot",
                "RightFoot", "Spine2", "LeftToeBase", "RightToeBase", "Neck", "LeftShoulder",
                "RightShoulder", "Head", "LeftArm", "RightArm", "LeftForeArm", "RightForeArm",
                "LeftHand", "RightHand")


def bvh_text(frames: int = 30, scale: float = 100.0, names: tuple[str, ...] = MIXAMO_NAMES,
             rot_order: str = "ZYX", declared_frames: int | None = None, z_up: bool = False) -> str:
    """A BVH of the rest pose walking along +z (y up, or z up with ``z_up``), in units of
    1/scale metres; rotations are zero so FK gives the rest pose exactly."""
    rest = REST_YUP * scale
    if z_up:  # y-up -> z-up: (x, y, z) -> (x, -z, y) keeps the frame right-handed
        rest = np.stack([rest[:, 0], -rest[:, 2], rest[:, 1]], axis=1)
    children = {i: [j for j, p in enumerate(SMPL22_PARENTS) if p == i] for i in range(22)}
    lines = ["HIERARCHY"]

    def emit(j: int, depth: int) -> None:
        ind = "  " * depth
        p = SMPL22_PARENTS[j]
        off = rest[j] - (rest[p] if p >= 0 else 0.0)
        lines.append(f"{ind}{'ROOT' if p < 0 else 'JOINT'} {names[j]}")
        lines.append(f"{ind}{{")
        lines.append(f"{ind}  OFFSET {off[0]:.6f} {off[1]:.6f} {off[2]:.6f}")
        rot = " ".join(f"{a}rotation" for a in rot_order)
        lines.append(f"{ind}  CHANNELS {'6 Xposition Yposition Zposition ' if p < 0 else '3 '}{rot}")
        for c in children[j]:
            emit(c, depth + 1)
        if not children[j]:
            lines.extend([f"{ind}  End Site", f"{ind}  {{", f"{ind}    OFFSET 0 0 0", f"{ind}  }}"])
        lines.append(f"{ind}}}")

    emit(0, 0)
    lines += ["MOTION", f"Frames: {declared_frames or frames}", "Frame Time: 0.033333"]
    for t in range(frames):
        fwd = 1.0 * scale * t / 30.0
        root = [0.0, 0.0, fwd] if not z_up else [0.0, -fwd, 0.0]
        lines.append(" ".join(f"{v:.5f}" for v in root + [0.0] * 3 + [0.0] * 3 * 21))
    return "\n".join(lines) + "\n"


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def test_rest_pose_is_a_plausible_body() -> None:
    assert REST_YUP.shape == (22, 3) and len(SMPL22) == 22
    assert REST_YUP[KP["head"], 1] > REST_YUP[KP["neck"], 1] > REST_YUP[KP["pelvis"], 1] > REST_YUP[KP["left_knee"], 1]
    assert REST_YUP[KP["left_hip"], 0] > 0 > REST_YUP[KP["right_hip"], 0]  # left at +x when facing +z


def test_bvh_text_declares_its_frames(tmp_path: Path) -> None:
    txt = bvh_text(frames=5)
    assert "Frames: 5" in txt and txt.count("JOINT") == 21

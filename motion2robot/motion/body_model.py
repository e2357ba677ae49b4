"""SMPL-family body models: rest joints and tree from a user's model file, and forward kinematics.

Only the rest joint positions J = J_regressor @ (v_template + shapedirs . betas) and the tree
(``kintree_table`` row 0) are used. The model file is the user's own (SMPL, SMPL-H, SMPL-X: the
licence does not allow shipping it); it is read as numpy arrays only (.npz without pickle) or with
the restricted unpickler (.pkl): a file asking for any code (chumpy, scipy) is refused.

Without a model file, :func:`approximate_model` gives the 22 body joints in a T-pose built from
the HumanML3D target skeleton's bone lengths and anatomical bone directions.

Frames: the model's own (SMPL: y up, facing +z, subject's left +x), metres.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motion2robot.motion.checks import fail
from motion2robot.motion.human import SMPL22_PARENTS

REQUIRED_KEYS = ("v_template", "J_regressor", "kintree_table")
_FIX = "give the SMPL/SMPL-H/SMPL-X model file (.npz) with v_template, J_regressor and kintree_table"


@dataclass(frozen=True)
class BodyModel:
    """rest: (K, 3) rest joint positions, metres; parents: (K,) with -1 for the root; source: where
    it came from; approximate: True for the built-in skeleton."""

    rest: np.ndarray
    parents: tuple[int, ...]
    source: str
    approximate: bool = False


def _arrays(path: Path) -> tuple[dict, list[str]]:
    """The arrays a body model needs, and the names of everything the file holds."""
    with open(path, "rb") as fh:
        magic = fh.read(4)
    if magic.startswith(b"PK"):  # only the needed members are read (capped, no pickle)
        from motion2robot.motion.archive import read_npz_members

        members = read_npz_members(path, (*REQUIRED_KEYS, "shapedirs"))
        return dict(members), members.names
    from motion2robot.motion.safe_pickle import restricted_load

    with open(path, "rb") as fh:
        obj = restricted_load(path, fh)
    if not isinstance(obj, dict):
        raise fail(path, f"holds a {type(obj).__name__}, not a body-model dict", _FIX)
    return obj, sorted(map(str, obj))


def load_body_model(path: str | Path, betas: np.ndarray | None = None) -> BodyModel:
    """Rest joints and tree of a model file; ``betas`` shape it when the file has ``shapedirs``."""
    path = Path(path)
    if not path.is_file():
        raise fail(path, "--body-model file not found", _FIX)
    d, names = _arrays(path)
    missing = [k for k in REQUIRED_KEYS if k not in d]
    if missing:
        raise fail(path, f"is missing {', '.join(missing)} (keys: {', '.join(names[:10])})", _FIX)
    try:
        v = np.asarray(d["v_template"], dtype=np.float64)
        jr = np.asarray(d["J_regressor"], dtype=np.float64)
        kin = np.asarray(d["kintree_table"]).astype(np.int64)
    except (TypeError, ValueError):
        raise fail(path, "has non-numeric v_template / J_regressor / kintree_table", _FIX) from None
    if v.ndim != 2 or v.shape[1] != 3 or jr.ndim != 2 or jr.shape[1] != v.shape[0] or kin.ndim != 2 \
            or kin.shape[1] != jr.shape[0] or jr.shape[0] < 22:
        raise fail(path, f"has inconsistent shapes (v_template {v.shape}, J_regressor {jr.shape}, "
                         f"kintree_table {kin.shape}; needs (V,3), (K>=22,V), (2,K))", _FIX)
    note = ""
    if betas is not None and "shapedirs" in d:
        sd = np.asarray(d["shapedirs"], dtype=np.float64)
        b = np.asarray(betas, dtype=np.float64).reshape(-1)
        n = min(b.size, sd.shape[-1]) if sd.ndim == 3 and sd.shape[:2] == v.shape else 0
        if n:
            v = v + sd[..., :n] @ b[:n]
            note = f", shaped with {n} betas"
    parents = kin[0].copy()
    parents[0] = -1
    if np.any(parents[1:] < 0) or np.any(parents[1:] >= np.arange(1, parents.size)):
        raise fail(path, "has a kintree_table whose parents do not come before their children", _FIX)
    return BodyModel(jr @ v, tuple(int(p) for p in parents), f"{path.name}{note}")


#: Bone lengths (metres) of the HumanML3D target skeleton, measured on its joints files
#: (symmetrised); index = child joint in SMPL22 order.
_HUMANML3D_BONES = (0.0, 0.1065, 0.1065, 0.1316, 0.3919, 0.3919, 0.1432, 0.4290, 0.4290, 0.0574, 0.1464,
                    0.1464, 0.2194, 0.1405, 0.1405, 0.1030, 0.1273, 0.1273, 0.2600, 0.2600, 0.2680, 0.2680)
#: Bone directions of a T-pose in the SMPL frame (y up, +z forward, left +x), parent to child.
_TPOSE_DIRECTIONS = (
    (0, 0, 0), (0.6, -0.8, -0.05), (-0.6, -0.8, -0.05), (0, 0.97, -0.24), (0.09, -1, 0), (-0.09, -1, 0),
    (0, 1, 0.03), (-0.03, -1, -0.1), (0.03, -1, -0.1), (0, 0.9, 0.43), (0.2, -0.42, 0.89), (-0.2, -0.42, 0.89),
    (0, 0.98, -0.2), (0.53, 0.82, -0.23), (-0.53, 0.82, -0.23), (0.06, 0.78, 0.62), (0.95, 0.32, -0.09),
    (-0.95, 0.32, -0.09), (1, -0.05, -0.1), (-1, -0.05, -0.1), (1, 0.04, 0), (-1, 0.04, 0),
)


def approximate_model() -> BodyModel:
    """The built-in 22-joint T-pose: HumanML3D bone lengths along anatomical directions."""
    rest = np.zeros((22, 3))
    for j, p in enumerate(SMPL22_PARENTS):
        if p >= 0:
            d = np.asarray(_TPOSE_DIRECTIONS[j], dtype=np.float64)
            rest[j] = rest[p] + _HUMANML3D_BONES[j] * d / np.linalg.norm(d)
    return BodyModel(rest, SMPL22_PARENTS, "built-in approximate skeleton", approximate=True)


def joint_positions(model: BodyModel, rotations: np.ndarray, trans: np.ndarray) -> np.ndarray:
    """Forward kinematics of the first K joints: rotations (T, K, 3, 3) local (parent-relative;
    joint 0: global orientation), trans (T, 3) root translation -> (T, K, 3) positions, metres,
    model frame. Joint k sits at its parent's position plus the parent's global rotation applied
    to its rest offset J_k - J_parent; the root at trans + J_0."""
    t, k = rotations.shape[:2]
    if k > len(model.parents):
        raise ValueError(f"{k} joint rotations for a model of {len(model.parents)} joints")
    glob = np.empty((t, k, 3, 3))
    pos = np.empty((t, k, 3))
    glob[:, 0] = rotations[:, 0]
    pos[:, 0] = trans + model.rest[0]
    for j in range(1, k):
        p = model.parents[j]
        glob[:, j] = glob[:, p] @ rotations[:, j]
        pos[:, j] = pos[:, p] + glob[:, p] @ (model.rest[j] - model.rest[p])
    return pos

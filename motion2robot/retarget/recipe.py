"""What a robot's generated problem code depends on, as one digest, so that a process finds the
compiled library in the cache without building the casadi graph first (op3: 2.3 s of graph
building and 0.6 s of lane source generation in every process; the G1: ~7 s).

The digest covers everything the graph is made from, and more rather than less: the source text
of the modules the graph and its code are made by (:data:`GRAPH_MODULES`, which a test keeps closed
under their imports from ``retarget`` and ``robot``, and every module of ``motion2robot.robot``;
a change to them makes a new key, a change to the stages around the solve does not; modules
elsewhere only make data the spec carries), the casadi and numpy versions, the compiler flags and lane width, the MuJoCo model's
kinematic arrays (bodies, joints, sites), the robot's keypoint/sole/foot/nominal data, and every
field of the :class:`~motion2robot.retarget.problem.ProblemSpec` (collision pairs with their
capsule and polytope numbers, layout, leg length, local axes). A stale library would give wrong
answers silently; a missed hit only costs the build.
"""

from __future__ import annotations

import dataclasses
import hashlib
from pathlib import Path

import casadi as ca
import numpy as np

#: MjModel arrays the kinematics and the problem read.
MODEL_ARRAYS = ("body_parentid", "body_pos", "body_quat", "body_ipos", "body_iquat", "body_mass",
                "body_jntnum", "body_jntadr", "jnt_type", "jnt_bodyid", "jnt_qposadr", "jnt_dofadr",
                "jnt_axis", "jnt_pos", "site_bodyid", "site_pos", "site_quat")
#: Robot fields the problem reads.
ROBOT_FIELDS = ("joint_ids", "nominal_qpos", "keypoints", "keypoint_sites", "keypoint_weights", "sole_sites",
                "foot_bodies", "root_body", "torso_body")
#: Modules (paths below the package) whose code builds the graph or its generated code.
GRAPH_MODULES = ("retarget/problem.py", "retarget/compiled.py", "retarget/lanes.py", "retarget/native.py",
                 "retarget/collision.py", "retarget/capsule_fit.py", "retarget/polytope.py",
                 "retarget/joint_cuts.py", "retarget/costs.py", "retarget/recipe.py",
                 "validate/collision.py", "validate/models.py", "util/cache.py")
_PACKAGE = Path(__file__).resolve().parent.parent


def graph_sources() -> list[Path]:
    """The source files hashed into the digest: :data:`GRAPH_MODULES`, the cost terms
    (``retarget/terms/*.py``) and ``robot/*.py``."""
    return ([_PACKAGE / m for m in GRAPH_MODULES] + sorted((_PACKAGE / "retarget" / "terms").glob("*.py"))
            + sorted((_PACKAGE / "robot").glob("*.py")))


def _feed(h, x) -> None:
    """Add ``x`` to hash ``h`` unambiguously (type tags, shapes, raw bytes of arrays)."""
    if isinstance(x, np.ndarray):
        h.update(f"nd{x.dtype.str}{x.shape}".encode())
        h.update(np.ascontiguousarray(x).tobytes())
    elif dataclasses.is_dataclass(x) and not isinstance(x, type):
        h.update(type(x).__name__.encode())
        for f in dataclasses.fields(x):
            h.update(f.name.encode())
            _feed(h, getattr(x, f.name))
    elif isinstance(x, dict):
        h.update(b"dict")
        for k in sorted(x, key=repr):
            _feed(h, k)
            _feed(h, x[k])
    elif isinstance(x, (list, tuple)):
        h.update(f"seq{len(x)}".encode())
        for v in x:
            _feed(h, v)
    elif isinstance(x, (str, int, float, bool, slice, np.generic)) or x is None:
        h.update(f"{type(x).__name__}:{x!r};".encode())
    else:
        raise TypeError(f"cannot hash {type(x).__name__} into the problem recipe")


def recipe_digest(spec, build: str) -> str:
    """Hex digest of what ``spec``'s generated code depends on; ``build`` names the code
    generator's settings (flags, lane width)."""
    h = hashlib.sha256(b"motion2robot problem recipe 2")
    for path in graph_sources():
        h.update(path.relative_to(_PACKAGE).as_posix().encode())
        h.update(path.read_bytes())
    _feed(h, (ca.__version__, np.__version__, build))
    model = spec.robot.model
    for name in MODEL_ARRAYS:
        _feed(h, np.asarray(getattr(model, name)))
    for name in ROBOT_FIELDS:
        value = getattr(spec.robot, name)
        _feed(h, np.asarray(value) if not isinstance(value, (int, np.integer)) else int(value))
    for f in dataclasses.fields(spec):
        if f.name != "robot":
            _feed(h, getattr(spec, f.name))
    return h.hexdigest()[:24]

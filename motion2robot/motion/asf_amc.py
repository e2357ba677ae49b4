"""Acclaim ASF (skeleton) / AMC (motion) files, as used by the CMU mocap database: parse the
text and run forward kinematics, vectorised over frames.

Conventions (the Acclaim/CMU ones):

* An Euler triple with order "XYZ" (``axis ... XYZ``, ``dof rx ry rz``, ``:root order ... RX RY RZ``)
  is applied first-listed first, about fixed axes: R = R_z @ R_y @ R_x (the same matrix as BVH
  channels "Zrotation Yrotation Xrotation"). Angles in degrees unless ``:units angle rad`` /
  ``:RADIANS``.
* Bone b has a constant frame C_b (its ``axis`` line) and a per-frame motion M_b composed from its
  AMC dof values; its global rotation is L_b = L_parent @ C_b @ M_b @ C_b^-1 and its END point is
  parent's end + L_b @ (direction * length). A bone's START is its parent's end (the root's
  position for the root's children). Bones without dofs keep M_b = I.
* Root: position = ``:root position`` + the AMC TX TY TZ; rotation L_root = C @ M @ C^-1 with C from
  ``:root orientation`` (in the ``:root axis`` order) and M from the AMC RX RY RZ (in ``order``).

Positions come out in the file's own axes (CMU: y up) and length units (see
:attr:`AsfSkeleton.length_unit`). Only rotational dofs (rx, ry, rz) are supported on bones.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motion2robot.motion.bvh import _axis_rotations
from motion2robot.motion.checks import fail


@dataclass(frozen=True)
class AsfBone:
    """direction: unit vector (3,) in the global rest frame; length in file units; axis: (3,)
    angles (file angle unit) applied in ``axis_order``; dofs: e.g. ("rx", "ry", "rz")."""

    name: str
    direction: np.ndarray
    length: float
    axis: np.ndarray
    axis_order: str
    dofs: tuple[str, ...]


@dataclass(frozen=True)
class AsfSkeleton:
    """bones by name; parents {bone: parent bone or "root"}; order: bones parents-first.
    length_unit: the ``:units length`` factor (CMU 0.45: 1 unit = 1/0.45 inch); degrees: angle
    unit of ``axis``/``orientation``; root_order: AMC root channels, e.g. ("TX", ..., "RZ")."""

    bones: dict[str, AsfBone]
    parents: dict[str, str]
    order: tuple[str, ...]
    length_unit: float | None
    degrees: bool
    root_order: tuple[str, ...]
    root_axis_order: str
    root_position: np.ndarray
    root_orientation: np.ndarray


@dataclass(frozen=True)
class AmcMotion:
    """values {"root" or bone: (T, n_dofs)} in the AMC's order; first_frame: the first frame
    number in the file; degrees: angle unit of the values."""

    values: dict[str, np.ndarray]
    first_frame: int
    degrees: bool

    @property
    def num_frames(self) -> int:
        return next(iter(self.values.values())).shape[0]


def _sections(text: str) -> dict[str, list[list[str]]]:
    """{":keyword": [tokens of each line until the next keyword]}, comments dropped."""
    out: dict[str, list[list[str]]] = {}
    current: list[list[str]] | None = None
    for line in text.splitlines():
        toks = line.split("#", 1)[0].split()
        if not toks:
            continue
        if toks[0].startswith(":"):
            current = out.setdefault(toks[0].lower(), [])
            if len(toks) > 1:
                current.append(toks[1:])
        elif current is not None:
            current.append(toks)
    return out


def _floats(path: Path, toks: list[str], n: int, what: str) -> np.ndarray:
    try:
        vals = np.array([float(t) for t in toks[:n]])
    except ValueError:
        vals = np.array([])
    if vals.size != n:
        raise fail(path, f"has a malformed {what} line ({' '.join(toks)!r}, expected {n} numbers)",
                   "fix the ASF or re-export it")
    return vals


def _order(path: Path, token: str, what: str) -> str:
    o = token.upper()
    if sorted(o) != ["X", "Y", "Z"]:
        raise fail(path, f"has an invalid rotation order {token!r} in {what}", "use a permutation of XYZ")
    return o


def _parse_bone(path: Path, lines: list[list[str]], degrees: bool) -> AsfBone:
    fields: dict[str, list[str]] = {}
    dofs: tuple[str, ...] = ()
    for toks in lines:
        key = toks[0].lower()
        if key == "dof":
            dofs = tuple(t.lower() for t in toks[1:])
        else:  # name, direction, length, axis (id, limits and others are not needed)
            fields[key] = toks[1:]
    name = (fields.get("name") or ["?"])[0]
    for key in ("name", "direction", "length", "axis"):
        if not fields.get(key):
            raise fail(path, f"bone {name!r} in :bonedata has no {key!r} line", "fix the ASF or re-export it")
    bad = [d for d in dofs if d not in ("rx", "ry", "rz")]
    if bad:
        raise fail(path, f"bone {name!r} has dofs {bad}, but only rotational dofs (rx ry rz) are supported",
                   "re-export the skeleton without translation/length dofs")
    direction = _floats(path, fields["direction"], 3, f"'direction' (bone {name})")
    norm = float(np.linalg.norm(direction))
    length = float(_floats(path, fields["length"], 1, f"'length' (bone {name})")[0])
    axis_toks = fields["axis"]
    if len(axis_toks) < 4:
        raise fail(path, f"bone {name!r} has a malformed 'axis' line (expected 3 angles and an order)",
                   "write e.g. 'axis 0 0 20 XYZ'")
    axis = _floats(path, axis_toks, 3, f"'axis' (bone {name})")
    if norm < 1e-12 and length > 0:
        raise fail(path, f"bone {name!r} has a zero direction vector", "fix the ASF or re-export it")
    return AsfBone(name, direction / norm if norm else direction, length, axis if degrees else np.rad2deg(axis),
                   _order(path, axis_toks[3], f"bone {name}"), dofs)


def parse_asf(path: str | Path) -> AsfSkeleton:
    """Parse an ASF skeleton; one-line InputFileError for any structural problem."""
    path = Path(path)
    text = path.read_text(errors="replace")
    sec = _sections(text)
    for key in (":root", ":bonedata", ":hierarchy"):
        if key not in sec:
            raise fail(path, f"is not a valid ASF skeleton (no {key} section)",
                       "give the subject's .asf file (e.g. 01.asf for 01_01.amc)")
    units = {t[0].lower(): t[1:] for t in sec.get(":units", []) if len(t) >= 2}
    degrees = units.get("angle", ["deg"])[0].lower().startswith("deg")
    length_unit = float(units["length"][0]) if "length" in units else None
    if length_unit is not None and not length_unit > 0:
        raise fail(path, f"has ':units length {length_unit}'", "use a positive length factor (CMU: 0.45)")
    root = {t[0].lower(): t[1:] for t in sec[":root"]}
    root_order = tuple(t.upper() for t in root.get("order", ["TX", "TY", "TZ", "RX", "RY", "RZ"]))
    if sorted(root_order) != ["RX", "RY", "RZ", "TX", "TY", "TZ"]:
        raise fail(path, f"has ':root order {' '.join(root_order)}'", "use the six channels TX TY TZ RX RY RZ")
    root_axis = _order(path, root.get("axis", ["XYZ"])[0], ":root axis")
    root_pos = _floats(path, root.get("position", ["0", "0", "0"]), 3, ":root position")
    root_ori = _floats(path, root.get("orientation", ["0", "0", "0"]), 3, ":root orientation")
    bones: dict[str, AsfBone] = {}
    block: list[list[str]] | None = None
    for toks in sec[":bonedata"]:
        key = toks[0].lower()
        if key == "begin":
            block = []
        elif key == "end":
            if block is None:
                raise fail(path, "has an 'end' without 'begin' in :bonedata", "fix the ASF or re-export it")
            bone = _parse_bone(path, block, degrees)
            bones[bone.name] = bone
            block = None
        elif block is not None:
            block.append(toks)
    if block is not None:
        raise fail(path, "is truncated: a :bonedata block has no 'end'", "re-export or re-download the ASF")
    parents: dict[str, str] = {}
    for toks in sec[":hierarchy"]:
        if toks[0].lower() in ("begin", "end"):
            continue
        for child in toks[1:]:
            if child == "root":
                raise fail(path, f":hierarchy makes the root a child of {toks[0]!r}", "fix the ASF hierarchy")
            for n in (toks[0], child):
                if n != "root" and n not in bones:
                    raise fail(path, f":hierarchy names bone {n!r}, which :bonedata does not define",
                               "fix the ASF hierarchy or re-export it")
            parents[child] = toks[0]
    order: list[str] = []
    frontier = ["root"]
    while frontier:  # breadth-first from the root: parents before children
        kids = [c for p in frontier for c in parents if parents[c] == p]
        order.extend(kids)
        frontier = kids
    unreached = [b for b in bones if b not in order]
    if unreached:
        raise fail(path, f"has bones not connected to the root in :hierarchy ({', '.join(unreached[:5])})",
                   "fix the ASF hierarchy or re-export it")
    return AsfSkeleton(bones, parents, tuple(order), length_unit, degrees, root_order, root_axis,
                       root_pos, root_ori if degrees else np.rad2deg(root_ori))


def _amc_lines(path: Path, degrees: bool) -> tuple[list[str], bool]:
    """(non-empty, non-comment lines from the first frame number on, stripped; angle unit after
    the ``:DEGREES`` / ``:RADIANS`` header)."""
    lines = path.read_text(errors="replace").splitlines()
    for i, line in enumerate(lines):
        s = line.strip()
        if not s or s[0] == "#":
            continue
        if s[0] == ":":
            degrees = {":DEGREES": True, ":RADIANS": False}.get(s.split()[0].upper(), degrees)
            continue
        if not s.isdigit():
            raise fail(path, f"has data before the first frame number ({s[:40]!r})",
                       "give a valid AMC file (header, then frame numbers each followed by bone lines)")
        body = [t for t in (ln.strip() for ln in lines[i:]) if t and t[0] != "#"]
        return body, degrees
    raise fail(path, "holds no frames (no frame-number lines)", "give a valid AMC motion file")


def _parse_regular(lines: list[str], expected: dict[str, int]) -> tuple[dict[str, np.ndarray], int] | None:
    """Fast path, vectorised per bone: every frame lists the same bones in the same order with the
    expected value counts and the frame numbers are contiguous. None when anything differs (the
    general parser then finds and names the problem)."""
    block = next((k for k in range(1, len(lines)) if lines[k].isdigit()), len(lines))
    n = len(lines) // block
    if block - 1 != len(expected) or len(lines) % block:
        return None
    numbers = lines[0::block]
    if not all(map(str.isdigit, numbers)):
        return None
    fn = np.array(numbers, dtype=np.int64)
    if (np.diff(fn) != 1).any():
        return None
    values: dict[str, np.ndarray] = {}
    for j in range(1, block):
        group = lines[j::block]
        name = group[0].split(None, 1)[0]
        k = expected.get(name)
        tokens = " ".join(group).split()
        if k is None or name in values or len(tokens) != n * (k + 1):
            return None
        if tokens[0::k + 1].count(name) != n:
            return None
        del tokens[0::k + 1]
        try:
            values[name] = np.array(list(map(float, tokens)), dtype=np.float64).reshape(n, k)
        except ValueError:
            return None
    return values, int(fn[0])


def _parse_general(path: Path, lines: list[str], expected: dict[str, int], skeleton: AsfSkeleton,
                   skeleton_path: str | Path) -> tuple[dict[str, np.ndarray], int]:
    """Line by line, any bone order; names the first problem in a one-line InputFileError."""
    names: list[str] = []
    rows: list[list[str]] = []
    frame_of_row: list[int] = []
    frame_numbers: list[int] = []
    for s in lines:
        if s.isdigit():
            frame_numbers.append(int(s))
            continue
        parts = s.split()
        names.append(parts[0])
        rows.append(parts[1:])
        frame_of_row.append(len(frame_numbers) - 1)
    n = len(frame_numbers)
    fn = np.asarray(frame_numbers)
    gaps = np.flatnonzero(np.diff(fn) != 1)
    if gaps.size:
        i = int(gaps[0])
        raise fail(path, f"has non-contiguous frame numbers ({fn[i]} is followed by {fn[i + 1]})",
                   "re-export the take or fix the frame numbering")
    by_bone: dict[str, list[int]] = {}
    for k, name in enumerate(names):
        by_bone.setdefault(name, []).append(k)
    unknown = [b for b in by_bone if b not in expected]
    if unknown:
        what = "has no dofs in" if all(b in skeleton.bones for b in unknown) else "is not in"
        raise fail(path, f"bone {unknown[0]!r} {what} the skeleton {skeleton_path}",
                   "give the .asf this motion was recorded with (--skeleton)")
    frame_arr = np.asarray(frame_of_row)
    values: dict[str, np.ndarray] = {}
    for bone, count in expected.items():
        idx = by_bone.get(bone, [])
        frames = frame_arr[idx]
        if len(idx) != n or (frames != np.arange(n)).any():
            have = np.zeros(n, bool)
            have[frames] = True
            missing = np.flatnonzero(~have)
            if missing.size and missing[0] == n - 1 and have[:-1].all():
                last = {names[k] for k in np.flatnonzero(frame_arr == n - 1)}
                lacking = [b for b in expected if b not in last]
                raise fail(path, f"is truncated: the last frame ({fn[-1]}) lacks {len(lacking)} of "
                                 f"{len(expected)} bones ({', '.join(lacking[:4])}{' ...' if len(lacking) > 4 else ''})",
                           "re-export or re-download the AMC (or delete the incomplete last frame)")
            first = int(fn[missing[0]]) if missing.size else int(fn[np.flatnonzero(np.bincount(frames) > 1)[0]])
            raise fail(path, f"frame {first} lists bone {bone!r} {'not at all' if missing.size else 'twice'}",
                       "give a fully specified AMC (every bone once per frame)")
        sub = [rows[k] for k in idx]
        wrong = [i for i, r in enumerate(sub) if len(r) != count]
        if wrong:
            i = wrong[0]
            trunc = i == n - 1
            raise fail(path, f"{'is truncated: ' if trunc else ''}frame {fn[i]} gives {len(sub[i])} values for "
                             f"bone {bone!r}, the skeleton has {count} dofs",
                       "re-export or re-download the AMC" if trunc else
                       "give the .asf this motion was recorded with (--skeleton)")
        try:
            values[bone] = np.array(sub, dtype=np.float64).reshape(n, count)
        except ValueError:
            raise fail(path, f"has non-numeric values for bone {bone!r}", "re-export the AMC") from None
    return values, int(fn[0])


def parse_amc(path: str | Path, skeleton: AsfSkeleton, skeleton_path: str | Path = "the ASF") -> AmcMotion:
    """Parse an AMC motion for ``skeleton``: every frame must list every bone with dofs, with as
    many values as the bone has dofs, and frame numbers must be contiguous."""
    path = Path(path)
    lines, degrees = _amc_lines(path, skeleton.degrees)
    expected = {"root": len(skeleton.root_order)}
    expected.update({b: len(bone.dofs) for b, bone in skeleton.bones.items() if bone.dofs})
    parsed = _parse_regular(lines, expected) or _parse_general(path, lines, expected, skeleton, skeleton_path)
    return AmcMotion(parsed[0], parsed[1], degrees)


def euler_matrix(angles_deg: np.ndarray, order: str) -> np.ndarray:
    """(T, 3, 3) rotations from (T, 3) angles in degrees; angle i is about axis order[i], applied
    first-listed first about fixed axes (order "XYZ": R_z @ R_y @ R_x)."""
    angles_deg = np.atleast_2d(angles_deg)
    r = np.broadcast_to(np.eye(3), (angles_deg.shape[0], 3, 3))
    for i, a in enumerate(order):
        r = _axis_rotations(a, angles_deg[:, i]) @ r
    return r


def _dof_matrix(values: np.ndarray, axes: str, degrees: bool) -> np.ndarray:
    """(T, 3, 3) motion rotation from (T, k) dof values about ``axes`` (e.g. "XZ"), first applied first."""
    return euler_matrix(values if degrees else np.rad2deg(values), axes)


def forward_kinematics(skeleton: AsfSkeleton, motion: AmcMotion) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """(root position (T, 3), {bone: END point (T, 3)}) in file axes and length units."""
    sk, t = skeleton, motion.num_frames
    root_vals = motion.values["root"]
    col = {c: i for i, c in enumerate(sk.root_order)}
    trans = root_vals[:, [col["TX"], col["TY"], col["TZ"]]] + sk.root_position
    rot_cols = sorted(i for c, i in col.items() if c.startswith("R"))
    rot_axes = "".join(sk.root_order[i][1] for i in rot_cols)
    c = euler_matrix(sk.root_orientation, sk.root_axis_order)[0]
    m = _dof_matrix(root_vals[:, rot_cols], rot_axes, motion.degrees)
    glob = {"root": c @ m @ c.T}
    end = {"root": trans}
    for b in sk.order:
        bone, parent = sk.bones[b], sk.parents[b]
        c = euler_matrix(bone.axis, bone.axis_order)[0]
        if bone.dofs:
            m = _dof_matrix(motion.values[b], "".join(d[1].upper() for d in bone.dofs), motion.degrees)
            glob[b] = glob[parent] @ (c @ m @ c.T)
        else:
            glob[b] = glob[parent]
        end[b] = end[parent] + glob[b] @ (bone.direction * bone.length)
    root = end.pop("root")
    return root, end

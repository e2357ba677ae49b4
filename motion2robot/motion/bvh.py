"""BVH (Biovision hierarchy): parse the text and run forward kinematics, vectorised over frames.

Conventions: each joint's rotation channels compose in the order listed (intrinsic, parent to
child: R = R_a1(t1) @ R_a2(t2) @ R_a3(t3)), degrees. A joint's translation is its position
channels when it has them (Bandai-style 6-channel joints store their OFFSET there), else its
OFFSET; the root adds its OFFSET to its position channels (only shifts the whole body: the
floor is estimated from the feet later). End Sites become pseudo-joints named "<parent>_End", or by their
"End Site #name: X" comment when an exporter wrote one; other "#" comments are ignored.
Positions come out in the file's own axes and units.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import re

import numpy as np

from motion2robot.errors import InputWarning
from motion2robot.motion.checks import MAX_COORDINATE, fail


@dataclass(frozen=True)
class BvhSkeleton:
    """Joints in file order (End Sites included, channels empty), parents (-1 for root),
    offsets (J, 3), channels per joint, and the column of each joint's first channel."""

    names: tuple[str, ...]
    parents: tuple[int, ...]
    offsets: np.ndarray
    channels: tuple[tuple[str, ...], ...]
    first_column: tuple[int, ...]

    @property
    def num_channels(self) -> int:
        return sum(len(c) for c in self.channels)


@dataclass(frozen=True)
class BvhClip:
    skeleton: BvhSkeleton
    frame_time: float
    values: np.ndarray  # (T, C) channel values as in the file


_VALID_CHANNELS = {f"{a}{k}" for a in "XYZ" for k in ("position", "rotation")}


def _parse_hierarchy(path: Path, tokens: list[str]) -> tuple[BvhSkeleton, int]:
    names: list[str] = []
    parents: list[int] = []
    offsets: list[list[float]] = []
    channels: list[tuple[str, ...]] = []
    stack: list[int] = []
    i = 1  # after HIERARCHY
    pending: int | None = None
    try:
        while i < len(tokens):
            tok = tokens[i]
            if tok in ("ROOT", "JOINT"):
                if tok == "ROOT" and names:
                    raise fail(path, "holds more than one ROOT", "export one skeleton per file")
                names.append(tokens[i + 1])
                parents.append(stack[-1] if stack else -1)
                offsets.append([0.0, 0.0, 0.0])
                channels.append(())
                pending = len(names) - 1
                i += 2
            elif tok == "End":
                parent = stack[-1]
                named = tokens[i + 2].startswith("@")
                names.append(tokens[i + 2][1:] if named else f"{names[parent]}_End")
                i += 1 if named else 0
                parents.append(parent)
                offsets.append([0.0, 0.0, 0.0])
                channels.append(())
                pending = len(names) - 1
                i += 2  # "End Site"
            elif tok == "{":
                stack.append(pending)
                i += 1
            elif tok == "}":
                stack.pop()
                i += 1
            elif tok == "OFFSET":
                offsets[stack[-1]] = [float(t) for t in tokens[i + 1:i + 4]]
                i += 4
            elif tok == "CHANNELS":
                n = int(tokens[i + 1])
                ch = tuple(tokens[i + 2:i + 2 + n])
                bad = [c for c in ch if c not in _VALID_CHANNELS]
                if bad:
                    raise fail(path, f"joint {names[stack[-1]]} has unknown channels {bad}",
                               "use X/Y/Z position/rotation channels")
                channels[stack[-1]] = ch
                i += 2 + n
            elif tok == "MOTION":
                break
            else:
                raise fail(path, f"unexpected token {tok!r} in HIERARCHY", "check the file is valid BVH")
    except (IndexError, ValueError, TypeError):
        raise fail(path, "has a malformed HIERARCHY section", "re-export the BVH") from None
    if stack or not names or i >= len(tokens):
        raise fail(path, "has an unterminated HIERARCHY or no MOTION section", "re-export the BVH")
    cols, c = [], 0
    for ch in channels:
        cols.append(c)
        c += len(ch)
    skel = BvhSkeleton(tuple(names), tuple(parents), np.asarray(offsets, float), tuple(channels), tuple(cols))
    return skel, i


def parse_bvh(path: str | Path, strict: bool = False) -> BvhClip:
    """Parse a BVH file; one-line InputFileError for any structural problem. A 'Frames:' line that
    disagrees with the rows is a warning (:class:`InputWarning`; the rows are read), an error if
    ``strict``."""
    path = Path(path)
    text = path.read_text(errors="replace")
    if not text.strip():
        raise fail(path, "is empty", "re-export the BVH")
    head, sep, motion = text.partition("MOTION")
    head = re.sub(r"End\s+Site\s*#\s*name:\s*(\S+)", r"End Site @\1", head)  # named End Sites
    tokens = re.sub(r"#[^\n]*", " ", head).split()
    if not tokens or tokens[0] != "HIERARCHY" or not sep:
        raise fail(path, "is not a BVH file (needs HIERARCHY ... MOTION)", "give a .bvh file or pass --format")
    skel, _ = _parse_hierarchy(path, tokens + ["MOTION"])
    lines = motion.split("\n", 3)
    try:
        frames_line = next(ln for ln in lines[:3] if ln.strip().startswith("Frames:"))
        time_line = next(ln for ln in lines[:3] if ln.strip().startswith("Frame Time:"))
        n_frames = int(frames_line.split(":")[1])
        frame_time = float(time_line.split(":")[1])
    except (StopIteration, ValueError, IndexError):
        raise fail(path, "has no valid 'Frames:' / 'Frame Time:' lines after MOTION", "re-export the BVH") from None
    body = lines[3] if len(lines) > 3 else ""
    try:
        data = np.array(body.split(), dtype=np.float64)
    except ValueError:
        raise fail(path, "has non-numeric values in the MOTION data", "re-export the BVH") from None
    n_ch = skel.num_channels
    rows = data.size // n_ch if n_ch else 0
    if not n_ch or data.size % n_ch:
        raise fail(path, f"is truncated: the MOTION data holds {data.size / max(n_ch, 1):.6g} frames of {n_ch} "
                         f"channels ('Frames: {n_frames}'), not a whole number", "re-export the file")
    if n_frames != rows:  # trust the data, not the header, and say so
        what = f"'Frames: {n_frames}' but the MOTION data holds {rows} frames of {n_ch} channels"
        if strict:
            raise fail(path, what, "fix the 'Frames:' line (or drop --strict to read the rows)")
        warnings.warn(InputWarning(f"{path}: {what}; reading all {rows} frames (--strict refuses such files)"),
                      stacklevel=2)
    if not (math.isfinite(frame_time) and frame_time > 0):
        raise fail(path, f"has Frame Time {frame_time}", "fix 'Frame Time:' or pass --source-fps")
    values = data.reshape(rows, n_ch)
    bad = ~np.isfinite(values) | (np.abs(values) > MAX_COORDINATE)
    if bad.any():
        t, c = (int(x) for x in np.argwhere(bad)[0])
        raise fail(path, f"frame {t}, channel {c + 1} of the MOTION data is {values[t, c]:g} (not finite or beyond "
                         f"{MAX_COORDINATE:g}; {int(bad.any(axis=1).sum())} frame(s) in all)",
                   "fix or trim those frames in the source")
    return BvhClip(skel, frame_time, values)


def _axis_rotations(axis: str, deg: np.ndarray) -> np.ndarray:
    a = np.deg2rad(deg)
    c, s = np.cos(a), np.sin(a)
    r = np.zeros((a.shape[0], 3, 3))
    i = "XYZ".index(axis)
    j, k = (i + 1) % 3, (i + 2) % 3
    r[:, i, i] = 1.0
    r[:, j, j] = c
    r[:, k, k] = c
    r[:, j, k] = -s
    r[:, k, j] = s
    return r


def forward_kinematics(clip: BvhClip, needed: set[str] | None = None) -> dict[str, np.ndarray]:
    """Global positions {joint name: (T, 3)} in file units/axes; only ``needed`` joints (and their
    ancestors) are computed when given."""
    sk, v = clip.skeleton, clip.values
    t = v.shape[0]
    keep = set(range(len(sk.names)))
    if needed is not None:
        keep = set()
        for n in needed:
            j = sk.names.index(n)
            while j >= 0 and j not in keep:
                keep.add(j)
                j = sk.parents[j]
    rot: dict[int, np.ndarray] = {}
    pos: dict[int, np.ndarray] = {}
    for j in range(len(sk.names)):  # file order is topological
        if j not in keep:
            continue
        ch, c0, p = sk.channels[j], sk.first_column[j], sk.parents[j]
        trans = np.broadcast_to(sk.offsets[j], (t, 3)).copy()
        local = np.broadcast_to(np.eye(3), (t, 3, 3))
        pos_ch = [(k, c) for k, c in enumerate(ch) if c.endswith("position")]
        if pos_ch:
            if p >= 0:
                trans[:] = 0.0
            for k, c in pos_ch:
                trans[:, "XYZ".index(c[0])] += v[:, c0 + k]
        for k, c in enumerate(ch):
            if c.endswith("rotation"):
                local = local @ _axis_rotations(c[0], v[:, c0 + k])
        if p < 0:
            rot[j], pos[j] = local, trans
        else:
            pos[j] = pos[p] + np.einsum("tij,tj->ti", rot[p], trans)
            rot[j] = rot[p] @ local
    return {sk.names[j]: pos[j] for j in pos}

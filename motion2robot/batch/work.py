"""Work items of a batch: one per clip, expanded from files, folders and manifests.

An INPUT is
- a motion file (any extension; named explicitly, it is always tried);
- a folder: every file below it (recursively, sorted) whose extension is in :data:`MOTION_EXTENSIONS`;
  a generator's extra copies of one motion (MoMask's joints/_ik/BVH quartet) are skipped, see
  :mod:`~motion2robot.batch.layouts`.
  ``.npy`` files holding a 1-D array (a data set's ``Mean.npy`` / ``Std.npy`` feature statistics)
  are not motions and are *skipped* (listed in :attr:`Expansion.skipped`), not turned into error rows;
- a manifest (``.txt`` / ``.lst``): one path per line, relative to the manifest's folder; blank lines
  and lines starting with ``#`` are ignored; a listed folder or manifest is expanded in turn.

A multi-clip file (an MDM results dict, a (N, T, 22, 3) batch) becomes one item per clip. The clip
count is read cheaply in the driver: the ``.npy`` header (shape, dtype) for plain arrays, the dict
for pickled MDM results (restricted unpickler), the array in an ``.npz``; BVH / ASF-AMC / pickle
files hold one clip; anything else (``.pt``), and any file the cheap count fails on, is read once
with ``read_motion`` to count. A file that cannot be counted becomes one item with ``clip=None``
(key ``path#*``): its row carries the reader's message as the error.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
from numpy.lib import format as npformat

from motion2robot.batch.layouts import duplicate_outputs
from motion2robot.errors import UserError
from motion2robot.motion.formats import SCAN_SUFFIXES, SINGLE_CLIP_SUFFIXES
from motion2robot.util.files import UNREADABLE_FIX, special_file, unreadable

#: Extensions picked up when a folder is expanded (the format table's).
MOTION_EXTENSIONS = SCAN_SUFFIXES
#: Extensions read as manifests (one path per line).
MANIFEST_EXTENSIONS = (".txt", ".lst")
#: Extensions whose every format holds exactly one clip per file.
_SINGLE_CLIP = SINGLE_CLIP_SUFFIXES
#: Last axis sizes of per-frame feature vectors (HumanML3D, KIT, MotionFix 207-d, SMPL-H 135).
_FEATURE_DIMS = (263, 251, 207, 135)


@dataclass(frozen=True)
class WorkItem:
    """One clip to process. path: absolute file path; clip: index within the file, or None when
    the file could not be counted (the whole file, which will become an error row)."""

    path: str
    clip: int | None

    @property
    def key(self) -> str:
        """Stable identity used for resume: ``/abs/path.npy#3`` (``#*`` for an uncountable file)."""
        return f"{self.path}#{'*' if self.clip is None else self.clip}"


@dataclass(frozen=True)
class Expansion:
    """items: the clips in input order (duplicates removed); skipped: (path, why) of files in
    folders that are not motions; count_errors: {path: message} of files whose clips could not
    be counted (their single item carries clip None)."""

    items: tuple[WorkItem, ...]
    skipped: tuple[tuple[str, str], ...] = ()
    count_errors: dict[str, str] = field(default_factory=dict)


def one_line(err: BaseException) -> str:
    """An exception as one line: a UserError's own message, otherwise ``Type: message``."""
    text = str(err) if isinstance(err, UserError) else f"{type(err).__name__}: {err}"
    return " ".join(text.split()) or type(err).__name__


def _npy_header(path: Path) -> tuple[tuple[int, ...], np.dtype]:
    with open(path, "rb") as fh:
        major, _ = npformat.read_magic(fh)
        read = npformat.read_array_header_1_0 if major == 1 else npformat.read_array_header_2_0
        shape, _, dtype = read(fh)
    return tuple(shape), dtype


def _count_array(shape: tuple[int, ...]) -> int:
    """Clips in a plain array: (N, T, 22, 3) / (N, 22, 3, T) / (N, 263, 1, T) batches have N,
    (N, T, 263) feature batches have N, everything else one."""
    if len(shape) == 5:  # MLD "all in one": samples x repetitions
        return int(shape[0]) * int(shape[1])
    if len(shape) == 4:
        return int(shape[0])
    if len(shape) == 3 and shape[-1] in _FEATURE_DIMS:
        return int(shape[0])
    return 1


def count_clips(path: Path, read_options: Mapping[str, Any] | None = None) -> int | None:
    """Number of clips in a motion file, or None when it is not a motion (a 1-D ``.npy``:
    feature statistics). Raises on unreadable files (caller turns that into an error item)."""
    ext = path.suffix.lower()
    if ext in _SINGLE_CLIP:
        return 1
    if ext == ".npy":
        shape, dtype = _npy_header(path)
        if dtype.hasobject:
            from motion2robot.motion.safe_pickle import load_npy

            obj = load_npy(path)
            if isinstance(obj, np.ndarray) and obj.dtype.hasobject and obj.shape == ():
                obj = obj.item()
            if isinstance(obj, dict) and isinstance(obj.get("motion"), np.ndarray):
                return int(obj["motion"].shape[0]) if obj["motion"].ndim == 4 else 1
            if isinstance(obj, dict) and "pose" in obj:  # an editor's result: edited, source, target
                return sum(k in obj for k in ("pose", "pose_source", "pose_target"))
            return 1  # let the reader explain what is wrong with it
        if len(shape) <= 1:
            return None
        return _count_array(shape)
    if ext == ".pkl":
        from motion2robot.motion.safe_pickle import restricted_load

        with open(path, "rb") as fh:
            obj = restricted_load(path, fh)
        if isinstance(obj, dict) and "pose" in obj:  # an editor's result: edited, source, target
            return sum(k in obj for k in ("pose", "pose_source", "pose_target"))
        return 1
    if ext == ".npz":  # from the member's header: nothing decompressed, a bomb refused
        from motion2robot.motion.archive import npz_member_shape

        shape = npz_member_shape(path, "joints") or npz_member_shape(path, "positions")
        return _count_array(shape) if shape else 1
    from motion2robot.motion import read_motion  # .pt and unknown formats: read once

    return len(read_motion(path, **dict(read_options or {})))


def _read_manifest(path: Path) -> list[Path]:
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as err:
        raise UserError(f"{path}: cannot read the manifest ({err}); give a text file with one path per line") from err
    out = []
    for line in lines:
        line = line.strip()
        if line and not line.startswith("#"):
            p = Path(line).expanduser()
            out.append(p if p.is_absolute() else path.parent / p)
    return out


def _walk(inputs: Iterable[Path], explicit: bool, seen_manifests: set[Path]
          ) -> Iterable[tuple[Path, bool, str | None]]:
    """Yield (file, named_explicitly, why it is skipped or None) in order."""
    for p in inputs:
        if p.is_dir() and p.suffix.lower() not in MOTION_EXTENSIONS:
            # regular files, and anything else named like a motion (FIFO, device, broken link,
            # a directory x.npy): those become error rows instead of vanishing
            found = sorted(q for q in p.rglob("*") if q.suffix.lower() in MOTION_EXTENSIONS
                           and (q.is_file() or special_file(q) is not None))
            copies = duplicate_outputs(q for q in found if q.is_file())
            for f in found:
                yield f, False, copies.get(f)
        elif p.suffix.lower() in MANIFEST_EXTENSIONS:
            if not p.is_file():
                raise UserError(f"{p}: manifest not found; check the path")
            real = p.resolve()
            if real in seen_manifests:
                raise UserError(f"{p}: manifest lists itself (directly or through another); remove the loop")
            yield from _walk(_read_manifest(p), True, seen_manifests | {real})
        else:
            yield p, explicit, None


def expand_inputs(inputs: Sequence[str | Path], read_options: Mapping[str, Any] | None = None) -> Expansion:
    """Expand INPUTS (files, folders, manifests) into work items, one per clip.

    ``read_options`` (format, fps, ...) are passed to ``read_motion`` for files counted by reading them.
    A named path that does not exist raises :class:`UserError` (a typo should stop the batch
    before it starts); a file listed in a manifest that does not exist becomes an error item.
    """
    if not inputs:
        raise UserError("no INPUTS given; pass motion files, folders or a manifest (.txt, one path per line)")
    for p in inputs:
        if not Path(p).exists():
            raise UserError(f"{p}: no such file or folder; check the path")
    items: list[WorkItem] = []
    skipped: list[tuple[str, str]] = []
    errors: dict[str, str] = {}
    seen: set[str] = set()
    for f, explicit, why in _walk([Path(p).expanduser() for p in inputs], True, set()):
        # a dangling link is named by itself (its target is not there); other paths by their real file
        path = str(f.absolute() if f.is_symlink() and not f.exists() else f.resolve())
        if path in seen:
            continue
        seen.add(path)
        if why is not None:
            skipped.append((path, why))
            continue
        try:
            special = special_file(f)
            if special is not None:
                raise UserError(f"{f}: {special}, not a motion file; remove it or give a regular file")
            denied = unreadable(f)
            if denied is not None:
                raise UserError(f"{f}: {denied}; {UNREADABLE_FIX}")
            if not f.is_file():
                raise UserError(f"{f}: no such file; fix the manifest entry")
            try:
                n = count_clips(f, read_options)
            except UserError:
                raise
            except Exception:  # noqa: BLE001 - the reader words the problem for the user (or copes)
                from motion2robot.motion import read_motion

                n = len(read_motion(f, **dict(read_options or {})))
        except Exception as err:  # noqa: BLE001 - any unreadable file becomes an error row
            errors[path] = one_line(err)
            items.append(WorkItem(path, None))
            continue
        if n is None:
            if explicit:
                items.append(WorkItem(path, 0))  # named on purpose: let the reader say why not
            else:
                skipped.append((path, "1-D array (feature statistics such as Mean.npy/Std.npy), not a motion"))
            continue
        items.extend(WorkItem(path, i) for i in range(n))
    return Expansion(tuple(items), tuple(skipped), errors)

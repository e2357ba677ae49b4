"""What a caller may tell a reader (all optional; None means "detect" or "the format's default")."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Mapping


@dataclass(frozen=True)
class ReadOptions:
    """clip: index of the one clip to keep; fps: override the file's frame rate; mean/std: feature
    statistics files (.npy) for normalised 263-d input; units: "m"|"cm"|"mm"|"inch"|"cmu";
    up: "x"|"y"|"z" (or "-y" ...); name_map: TOML file or {keypoint: spec} for BVH skeletons;
    skeleton: the ASF file of an AMC take; stats: a model's statistics file (pickled mean/std dict)
    for normalised MotionFix/OmniME 207-d features; body_model: the user's SMPL/SMPL-H/SMPL-X model
    file for SMPL parameters; strict: refuse the approximate skeleton when there is none."""

    clip: int | None = None
    fps: float | None = None
    mean: str | Path | None = None
    std: str | Path | None = None
    units: str | None = None
    up: str | None = None
    name_map: str | Path | Mapping[str, str] | None = None
    skeleton: str | Path | None = None
    stats: str | Path | None = None
    body_model: str | Path | None = None
    strict: bool = False

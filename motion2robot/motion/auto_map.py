"""Automatic skeleton map: SMPL22 keypoints from joint names (tokens) checked against the tree.

Every joint name is read as a side and a body part (:mod:`~motion2robot.motion.name_tokens`).
Each leg and arm is then the set of one side's leg (arm) joints, ordered by the words they carry
(hip < knee < ankle < toes; collar < shoulder < elbow < wrist) and required to form one chain down
the tree; the pelvis is the top-most pelvis joint above both hips (else the hips' common ancestor);
the spine keypoints come from the spine joints on the path from the pelvis to the neck. Where a rig
holds two candidates for one keypoint (CMU's LHipJoint and LeftUpLeg), joints with a zero offset
from their parent (placeholders at the parent's position) give way to the others. A missing last
joint of a chain (toes, wrist, head) is the End Site below the joint before it, as IK-generated
files end their chains there. The result is a map in the preset language of
:mod:`~motion2robot.motion.skeletons` ({keypoint: [joints to average]}).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from motion2robot.motion.human import SMPL22
from motion2robot.motion.name_tokens import JointWords, arm_rank, classify, leg_rank

_LEG_KPS = ("hip", "knee", "ankle", "foot")
_ARM_KPS = ("collar", "shoulder", "elbow", "wrist")
#: A joint whose offset is below this fraction of the skeleton's largest offset sits on its parent.
_ZERO_OFFSET = 1e-4


class _Tree:
    def __init__(self, names: Sequence[str], parents: Sequence[int], offsets: np.ndarray,
                 end_sites: Sequence[bool]):
        self.names, self.parents, self.end = list(names), list(parents), list(end_sites)
        norms = np.linalg.norm(np.asarray(offsets, float).reshape(len(names), 3), axis=1)
        self.zero = norms < _ZERO_OFFSET * max(float(norms.max(initial=0.0)), 1e-12)
        self.depth = [0] * len(names)
        for j, p in enumerate(parents):  # file order is topological
            self.depth[j] = self.depth[p] + 1 if p >= 0 else 0

    def is_ancestor(self, a: int, b: int) -> bool:
        """True when a is a strict ancestor of b."""
        j = self.parents[b]
        while j >= 0:
            if j == a:
                return True
            j = self.parents[j]
        return False

    def path(self, a: int, b: int) -> list[int]:
        """Joints strictly between ancestor a and descendant b, top-down."""
        out, j = [], self.parents[b]
        while j >= 0 and j != a:
            out.append(j)
            j = self.parents[j]
        return out[::-1]

    def end_below(self, j: int) -> int | None:
        return next((k for k, p in enumerate(self.parents) if p == j and self.end[k]), None)

    def pick(self, cands: list[int]) -> int | None:
        """The top-most candidate, placeholders (zero offset) only when nothing else is left."""
        real = [j for j in cands if not self.zero[j]] or cands
        return min(real, key=lambda j: self.depth[j]) if real else None


def _chain(tree: _Tree, info: list[JointWords | None], side: str, limb: str) -> dict[int, int]:
    """{rank: joint} of one limb; ranks 0..3 where found, checked to go down the tree."""
    joints = [j for j, w in enumerate(info) if w and w.side == side and w.limb == limb and not w.twist]
    limb_words = {info[j].word for j in joints}  # type: ignore[union-attr]
    rank_of = leg_rank if limb == "leg" else arm_rank
    by_rank: dict[int, list[int]] = {}
    for j in joints:
        by_rank.setdefault(rank_of(info[j].word, limb_words), []).append(j)  # type: ignore[union-attr]
    out: dict[int, int] = {}
    for r in range(4):
        cands = [j for j in by_rank.get(r, []) if not out or tree.is_ancestor(out[max(out)], j)]
        picked = tree.pick(cands)
        if picked is None and r == 3 and 2 in out:
            picked = tree.end_below(out[2])
        if picked is not None:
            out[r] = picked
    return out


def auto_map(names: Sequence[str], parents: Sequence[int], offsets: np.ndarray,
             end_sites: Sequence[bool]) -> tuple[dict[str, list[str]], list[str]]:
    """({keypoint: [joint names to average]}, [keypoints it could not map]) for one skeleton.

    names/parents/offsets: the skeleton in file order (parents -1 for the root, offsets (J, 3));
    end_sites: True for End Site pseudo-joints (used only to end a chain).
    """
    tree = _Tree(names, parents, offsets, end_sites)
    info = [None if e else classify(n) for n, e in zip(names, end_sites)]
    got: dict[str, list[int]] = {}
    for limb, kps in (("leg", _LEG_KPS), ("arm", _ARM_KPS)):
        for side, prefix in (("L", "left_"), ("R", "right_")):
            for r, j in _chain(tree, info, side, limb).items():
                got[prefix + kps[r]] = [j]
    hips = [got[k][0] for k in ("left_hip", "right_hip") if k in got]
    if len(hips) == 2:
        pel = [j for j, w in enumerate(info) if w and w.word == "hips" or w and w.word == "pelvis"]
        above = [j for j in pel if all(tree.is_ancestor(j, h) for h in hips)]
        if above:
            got["pelvis"] = [min(above, key=lambda j: tree.depth[j])]
        else:
            common = [j for j in range(len(names)) if all(tree.is_ancestor(j, h) for h in hips)]
            if common:
                got["pelvis"] = [max(common, key=lambda j: tree.depth[j])]
    if "pelvis" in got:
        _spine(tree, info, got["pelvis"][0], got)
    mapping = {kp: [names[j] for j in got[kp]] for kp in SMPL22 if kp in got}
    return mapping, [kp for kp in SMPL22 if kp not in got]


def _spine(tree: _Tree, info: list[JointWords | None], pelvis: int, got: dict[str, list[int]]) -> None:
    heads = [j for j, w in enumerate(info) if w and w.word == "head" and tree.is_ancestor(pelvis, j)]
    head = tree.pick(heads)
    necks = [j for j, w in enumerate(info) if w and w.word == "neck" and tree.is_ancestor(pelvis, j)
             and (head is None or tree.is_ancestor(j, head))]
    neck = tree.pick(necks)
    if neck is None:
        return
    got["neck"] = [neck]
    if head is None:
        head = tree.end_below(neck)
    if head is not None:
        got["head"] = [head]
    spine = [j for j in tree.path(pelvis, neck) if info[j] and info[j].part_is_spine]  # type: ignore[union-attr]
    spine = [j for j in spine if not tree.zero[j]] or spine
    n = len(spine)
    if n >= 3:
        got.update(spine1=[spine[0]], spine2=[spine[-2]], spine3=[spine[-1]])
    elif n == 2:
        got.update(spine1=[spine[0]], spine2=[spine[1]], spine3=[spine[1], neck])
    elif n == 1:
        got.update(spine1=[spine[0]], spine2=[spine[0], neck], spine3=[spine[0], neck, neck])

"""Joint names as normalised tokens: side, body part, synonyms (data for the automatic skeleton map).

``"mixamorig:LeftUpLeg"``, ``"L_Thigh"``, ``"l_hip"``, ``"Left_hip"``, ``"UpperLeg_L"`` and CMU's
``"lfemur"`` all read as side L, part "upper leg". A name is split at namespaces, separators,
camelCase and digits; lowercase runs are segmented into known words ("lhipjoint" -> l hip joint);
adjacent words that form a known compound are joined ("fore arm" -> forearm). A name with any word
outside the vocabulary (fingers, "ShareBone", "j0") has no part: the automatic map ignores it.

Some words mean different joints in different rigs ("Shoulder" is the collar in Mixamo and the
upper arm in SMPL; "Foot" the ankle in Mixamo and the toes in SMPL; "Leg" the knee in Mixamo). Their
meaning is fixed per limb by the other words of that limb (:func:`leg_rank`, :func:`arm_rank`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache

SIDES = {"left": "L", "l": "L", "lft": "L", "right": "R", "r": "R", "rt": "R", "rgt": "R"}
#: Words that carry no meaning for the map (rig prefixes, "joint").
NOISE = frozenset({"cc", "base", "joint", "jnt", "bip", "mixamorig", "rl", "bone", "def", "bn"})
#: Word -> part. Parts: pelvis, spine, neck, head, root, twist, and the limb words below.
PARTS: dict[str, str] = {
    "pelvis": "pelvis", "hips": "pelvis", "root": "root", "twist": "twist",
    "spine": "spine", "chest": "spine", "upperchest": "spine", "waist": "spine", "abdomen": "spine",
    "torso": "spine", "back": "spine", "lowerback": "spine", "upperback": "spine",
    "neck": "neck", "head": "head",
}
#: Leg words and the leg joint they name (0 hip, 1 knee, 2 ankle, 3 toes); None: depends on the limb.
LEG_WORDS: dict[str, int | None] = {
    "hip": 0, "thigh": 0, "upleg": 0, "upperleg": 0, "femur": 0,
    "leg": None, "knee": 1, "calf": 1, "lowerleg": 1, "lowleg": 1, "shin": 1, "tibia": 1,
    "ankle": 2, "foot": None, "toe": 3, "toes": 3, "toebase": 3, "ball": 3,
}
#: Arm words and the arm joint they name (0 collar, 1 shoulder, 2 elbow, 3 wrist).
ARM_WORDS: dict[str, int | None] = {
    "collar": 0, "clavicle": 0, "shoulder": None, "arm": 1, "upperarm": 1, "uparm": 1, "humerus": 1,
    "forearm": 2, "elbow": 2, "lowerarm": 2, "radius": 2, "ulna": 2, "hand": 3, "wrist": 3,
}
_VOCAB = frozenset(SIDES) | NOISE | set(PARTS) | set(LEG_WORDS) | set(ARM_WORDS)


@dataclass(frozen=True)
class JointWords:
    """A joint name's meaning: side ("L", "R" or None), its part word (e.g. "upleg", "spine") and
    whether it is a twist bone."""

    side: str | None
    word: str
    twist: bool = False

    @property
    def part_is_spine(self) -> bool:
        return self.side is None and PARTS.get(self.word) == "spine"

    @property
    def limb(self) -> str | None:
        if self.side and self.word in LEG_WORDS:
            return "leg"
        if self.side and self.word in ARM_WORDS:
            return "arm"
        return None


def _segment(run: str) -> list[str] | None:
    """Split a lowercase run into vocabulary words (fewest words), or None."""
    best: list[list[str] | None] = [None] * (len(run) + 1)
    best[0] = []
    for i in range(1, len(run) + 1):
        for j in range(max(0, i - 12), i):
            if best[j] is not None and run[j:i] in _VOCAB:
                cand = best[j] + [run[j:i]]  # type: ignore[operator]
                if best[i] is None or len(cand) < len(best[i]):  # type: ignore[arg-type]
                    best[i] = cand
    return best[-1]


@lru_cache(maxsize=4096)
def words(name: str) -> tuple[str, ...]:
    """Normalised lowercase words of a joint name (digits dropped), compounds joined."""
    n = name.rsplit(":", 1)[-1]
    n = re.sub(r"([a-z])([A-Z])", r"\1 \2", n)
    n = re.sub(r"([A-Z]+)([A-Z][a-z])", r"\1 \2", n)
    raw = [w.lower() for w in re.split(r"[^A-Za-z]+", n) if w]
    out: list[str] = []
    for w in raw:
        seg = [w] if w in _VOCAB else _segment(w)
        out.extend(seg if seg is not None else [w])
    i, joined = 0, []
    while i < len(out):
        for k in (3, 2):
            if i + k <= len(out) and "".join(out[i:i + k]) in _VOCAB:
                joined.append("".join(out[i:i + k]))
                i += k
                break
        else:
            joined.append(out[i])
            i += 1
    return tuple(joined)


def classify(name: str) -> JointWords | None:
    """The joint's side and part word, or None when a word is unknown or there is no single part."""
    side, parts, twist = None, [], False
    for w in words(name):
        if w in NOISE:
            continue
        if w == "twist":
            twist = True
        elif w in SIDES:
            if side is not None and side != SIDES[w]:
                return None
            side = SIDES[w]
        elif w in _VOCAB:
            parts.append(w)
        else:
            return None
    if len(set(parts)) != 1:
        return None
    word = parts[0]
    if word == "hip" and side is None:
        word = "hips"  # an unsided hip is the pelvis (CC_Base_Hip)
    if side is None and (word in LEG_WORDS or word in ARM_WORDS):
        return None
    if side is not None and word not in LEG_WORDS and word not in ARM_WORDS:
        return None
    return JointWords(side, word, twist)


def leg_rank(word: str, limb_words: set[str]) -> int:
    """Leg joint (0 hip .. 3 toes) a word names, given every word of the same leg."""
    rank = LEG_WORDS[word]
    if rank is not None:
        return rank
    if word == "leg":  # Mixamo's LeftLeg is the knee when an upper-leg word is present
        return 1 if limb_words & {"hip", "thigh", "upleg", "upperleg", "femur"} else 0
    return 3 if "ankle" in limb_words else 2  # "foot": the toes beside an ankle, else the ankle


def arm_rank(word: str, limb_words: set[str]) -> int:
    """Arm joint (0 collar .. 3 wrist) a word names, given every word of the same arm."""
    rank = ARM_WORDS[word]
    if rank is not None:
        return rank
    if limb_words & {"collar", "clavicle"}:  # "shoulder" beside a collar: the upper arm (SMPL)
        return 1
    return 0 if limb_words & {"arm", "upperarm", "uparm", "humerus"} else 1

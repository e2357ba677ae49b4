"""Human motion: the :class:`HumanMotion` type, readers for each format, and operations."""

from motion2robot.motion.contacts import detect_contacts, with_contacts
from motion2robot.motion.height import subject_height
from motion2robot.motion.human import KP, SMPL22, SMPL22_PARENTS, HumanMotion
from motion2robot.motion.ops import align_floor, align_heading, mirror, resample, trim
from motion2robot.motion.read import FORMATS, detect_format, read_motion
from motion2robot.motion.tensors import from_tensor

__all__ = [
    "HumanMotion", "SMPL22", "SMPL22_PARENTS", "KP", "FORMATS", "read_motion", "detect_format",
    "from_tensor", "resample", "trim", "align_floor", "align_heading", "mirror", "detect_contacts",
    "with_contacts", "subject_height",
]

"""motion2robot: generated human motion -> humanoid robot motion that is checked before it runs.

Pipeline: read (:mod:`motion2robot.motion`) -> retarget (:mod:`motion2robot.retarget`) ->
validate (:mod:`motion2robot.validate`) -> stream (:mod:`motion2robot.hardware`), in batch with
:mod:`motion2robot.batch`. Conventions everywhere: metres, radians, seconds, z up, x forward,
quaternions wxyz.
"""

__version__ = "0.1.0"

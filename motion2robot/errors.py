"""Errors a user can act on.

Every problem caused by input (a file, a flag, a robot config, a servo) is raised as a
:class:`UserError` whose message is ONE line naming the thing, the problem and the fix. The CLI
prints it on stderr and exits with code 2 (traceback only with ``--debug``).
"""

from __future__ import annotations


class UserError(Exception):
    """A problem with the user's input; ``str(err)`` is the one-line message shown to the user."""

    exit_code = 2

    def __init__(self, message: str):
        super().__init__(" ".join(str(message).split()))  # always one line


class InputFileError(UserError):
    """A file could not be read or has the wrong content."""


class RobotConfigError(UserError):
    """A robot name, model or config is unknown, missing or invalid."""


class SolverError(UserError):
    """The retargeting problem cannot be posed for this motion/robot (not a numerical failure)."""


class InputWarning(UserWarning):
    """Input was read, but with an assumption the user should know (one line, shown by the CLI as
    ``motion2robot: warning: ...``)."""


class MotionBatchError(UserError, ValueError):
    """Arrays or tensors given to the in-process API (:mod:`motion2robot.api`) cannot be taken as a
    batch of motions: wrong shape, padding without ``lengths``, lengths that do not fit."""

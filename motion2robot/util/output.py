"""Output paths checked before any work is done: a directory, or a folder that cannot be made, is
a one-line user error (not a traceback after the work, nor a stray ``.part`` file)."""

from __future__ import annotations

from pathlib import Path

from motion2robot.errors import InputFileError


def output_path(path: str | Path, what: str = "output", suffix: str = "") -> Path:
    """``path`` as a Path whose folder exists (made if needed); InputFileError if it is a directory
    or its folder cannot be made. ``suffix``: the file type, for the example file name."""
    p = Path(path)
    if p.is_dir():
        raise InputFileError(f"{p}: is a directory; give a file name for the {what}, e.g. {p / ('out' + (p.suffix or suffix))}")
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InputFileError(f"{p}: cannot create its folder for the {what} ({err.strerror}); "
                             "choose another path") from None
    return p

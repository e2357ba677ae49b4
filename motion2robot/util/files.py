"""What a path is when it is not a regular file: a reader must not open a FIFO (it blocks for
ever) nor a device, and a batch gives such entries an error row. A regular file this process may
not open (permissions) is named as such, not left to the reader's traceback."""

from __future__ import annotations

import os
import stat
from pathlib import Path


def special_file(path: str | Path) -> str | None:
    """"is a FIFO (named pipe)", "is a directory", ... for a path that exists but is no regular
    file, "is a broken symbolic link" for a dangling link; None for a regular or missing file."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return "is a broken symbolic link" if os.path.islink(path) else None
    except OSError as err:
        return f"cannot be examined ({err.strerror})"
    for test, what in ((stat.S_ISDIR, "is a directory"), (stat.S_ISFIFO, "is a FIFO (named pipe)"),
                       (stat.S_ISCHR, "is a character device"), (stat.S_ISBLK, "is a block device"),
                       (stat.S_ISSOCK, "is a socket")):
        if test(st.st_mode):
            return what
    return None


def unreadable(path: str | Path) -> str | None:
    """"cannot be read (Permission denied)" for an existing regular file this process may not
    open; None otherwise (also for special or missing files: see :func:`special_file`)."""
    if special_file(path) is not None or not os.path.isfile(path):
        return None
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except FileNotFoundError:
        return None
    except OSError as err:
        return f"cannot be read ({err.strerror})"
    os.close(fd)
    return None


#: The fix to name with :func:`unreadable`.
UNREADABLE_FIX = "check the file's permissions (e.g. chmod u+r) or read it as its owner"

"""The ``motion2robot`` command line.

Each subcommand lives in its own module ``motion2robot/cli/cmd_<name>.py`` exposing
``register(subparsers) -> None``; the module adds its parser and sets ``func=handler`` with
``handler(args) -> int``. This module finds them, runs the chosen one, and owns the error
convention: a :class:`~motion2robot.errors.UserError` becomes one line on stderr and exit code 2
(traceback only with ``--debug``), and so does a PermissionError (a file or folder the user may
not read or write, wherever it is met); Ctrl-C exits 130.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
import traceback
import warnings
from typing import NoReturn

from motion2robot import __version__
from motion2robot.errors import InputWarning, UserError

_default_showwarning = warnings.showwarning


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:  # noqa: ANN001
    """Input warnings as one line ``motion2robot: warning: ...``; others as Python prints them."""
    if issubclass(category, InputWarning):
        print(f"motion2robot: warning: {message}", file=sys.stderr)
    else:
        _default_showwarning(message, category, filename, lineno, file, line)

#: Order in which subcommands appear in ``--help`` (others follow alphabetically).
_ORDER = ["demo", "robots", "inspect", "retarget", "edit", "check", "sim", "stream", "servos", "batch", "batch-report", "score"]


def _command_modules() -> list[str]:
    names = [m.name for m in pkgutil.iter_modules(__path__) if m.name.startswith("cmd_")]
    key = {n: i for i, n in enumerate(_ORDER)}
    return sorted(names, key=lambda n: (key.get(n[4:].replace("_", "-"), len(key)), n))


class OneLineParser(argparse.ArgumentParser):
    """An argparse parser whose usage errors are one line ``motion2robot: error: ...`` and exit 2
    (subcommand parsers inherit it), like every other user error."""

    def error(self, message: str) -> NoReturn:
        sub = self.prog.split(" ", 1)[1] + ": " if " " in self.prog else ""
        print(f"motion2robot: error: {sub}{' '.join(message.split())} (see '{self.prog} --help')", file=sys.stderr)
        sys.exit(2)


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="motion2robot",
        description=(
            "Turn generated human motion (HumanML3D, MDM, BVH, tensors) into humanoid robot motion: "
            "retarget with casadi IK, check feasibility in MuJoCo, stream to Dynamixel servos."
        ),
        epilog="Run 'motion2robot COMMAND --help' for a command's options.",
    )
    parser.add_argument("--version", action="version", version=f"motion2robot {__version__}")
    parser.add_argument("--debug", action="store_true", help="show full tracebacks on errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in _command_modules():
        importlib.import_module(f"{__name__}.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the process exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    warnings.showwarning = _show_warning
    for stream in (sys.stdout, sys.stderr):  # a file name that is not UTF-8 prints as \xe9, never a crash
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    try:
        from motion2robot.viz.gl import import_mujoco

        import_mujoco()  # a broken MUJOCO_GL backend fails mujoco's import: make it the one-line error
        parser = build_parser()
        args = parser.parse_args(argv)
        if not getattr(args, "func", None):
            parser.print_help()
            return 2 if args.command is None and argv else 0
        return int(args.func(args) or 0)
    except UserError as err:
        if debug:
            traceback.print_exc()
        print(f"motion2robot: error: {err}", file=sys.stderr)
        return err.exit_code
    except KeyboardInterrupt:
        print("motion2robot: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except PermissionError as err:  # a file or folder this user may not read or write: never a bug
        if debug:
            traceback.print_exc()
        where = err.filename or "a file or folder"
        print(f"motion2robot: error: {where}: permission denied; check its permissions (or those of its folder) "
              "or choose another path", file=sys.stderr)
        return 2
    except Exception as err:  # a bug, not bad input: still one line unless --debug
        if debug:
            raise
        print(f"motion2robot: internal error: {type(err).__name__}: {err} "
              "(rerun with --debug for the traceback and please report it)", file=sys.stderr)
        return 3


def run() -> None:  # pragma: no cover - console script shim
    sys.exit(main())

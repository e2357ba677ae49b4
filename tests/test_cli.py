"""The command line: help for every subcommand, and the one-line error convention."""

import subprocess
import sys

import pytest

from motion2robot.cli import _command_modules, build_parser, main


def test_top_level_help(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--help"])
    assert e.value.code == 0
    assert "COMMAND" in capsys.readouterr().out


def test_every_subcommand_explains_itself(capsys):
    parser = build_parser()
    names = [m[4:].replace("_", "-") for m in _command_modules()]
    assert names, "no subcommands registered"
    for name in names:
        with pytest.raises(SystemExit) as e:
            main([name, "--help"])
        assert e.value.code == 0
        out = capsys.readouterr().out
        assert f"motion2robot {name}" in out and len(out) > 80


def test_unknown_command_exits_2(capsys):
    with pytest.raises(SystemExit) as e:
        main(["no-such-command"])
    assert e.value.code == 2


def test_console_entry_point_runs():
    r = subprocess.run([sys.executable, "-m", "motion2robot", "--version"], capture_output=True, text=True)
    assert r.returncode == 0 and "motion2robot" in r.stdout


def _actions(parser, prefix=""):
    import argparse

    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            for name, sub in a.choices.items():
                yield from _actions(sub, f"{prefix}{name} ")
        else:
            yield prefix.strip(), a


def test_every_numeric_option_is_checked_when_parsed():
    """Issue 20: 'Every numeric option is validated when it is parsed (finite, in range, with units
    in the message)': no option takes a bare float or int (which accept nan, inf, 0 and negatives),
    except clip indices, which the readers check against the file's clips."""
    index_options = {"--clip", "--source-clip", "--edit-clip"}
    bare = [f"{cmd} {a.option_strings[0]}" for cmd, a in _actions(build_parser())
            if a.type in (float, int) and not index_options & set(a.option_strings)]
    assert bare == []
    typed = [a for _, a in _actions(build_parser()) if getattr(a.type, "__qualname__", "") == "number.<locals>.parse"]
    assert len(typed) >= 25

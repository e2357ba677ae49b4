"""Every user error issue 20 names, from the corpus by name (the sampled test runs a sixth of the
corpus; these all run): one ``motion2robot: error: ...`` line naming the file or the option, exit 2.
An unreadable file is in tests/test_hostile_permissions.py (it needs a process without root's
file-permission capabilities)."""

from __future__ import annotations

import pytest

from tests.fuzz.corpus import CASES
from tests.fuzz.runner import run_case

ISSUE_CASES = {
    # 3. --rate not validated at all (0, negative, nan, inf)
    "rate": ["stream: --rate 0", "stream: --rate -1", "stream: --rate nan", "stream: --rate inf"],
    # 4. one value of 3e38 in a HumanML3D file made retarget write an all-NaN motion, exit 0
    "finite": ["retarget: 3e38 in a HumanML3D file", "retarget: 1e20 wrist"],
    # 7. "internal error", exit 3, for about 30 user mistakes
    "npy header": ["npy: structured dtype", "npy: negative shape"],
    "mdm dicts": ["mdm: string lengths", "mdm: numeric text", "mdm: non-string keys"],
    "npz": ["npz: fps 0", "npz: fps negative", "npz: fps NaN", "npz: fps text", "npz: fps array",
            "npz: object array member", "npz: bad CRC", "npz: truncated member"],
    "read options": ["option: --format npz for a .npy", "option: --source-fps -5", "option: --source-fps nan"],
    "outputs": ["retarget: -o is a directory", "check: --json is a directory"],
    "stream options": ["stream: --rate abc", "stream: --ramp-speed abc", "stream: --policy ramp_speed=abc"],
    "stream motions": ["stream: motion fps 0", "stream: motion fps NaN", "stream: motion fps inf",
                       "stream: motion with 0 frames", "stream: human motion"],
    "robot configs": ["robot config: ticks_per_rev 0", "robot config: ticks_per_rev negative",
                      "robot config: unknown servo model", "robot config: baud as text",
                      "robot config: servo for a joint that does not exist"],
    # 8. smaller problems
    "smaller": ["retarget: FIFO", "npz: 2.3 MB expanding to 528 MB", "stream: --latency-ms -1",
                "input: broken symlink", "input: directory named x.npy"],
}
#: Options an error line may name instead of a file (-o and --json name the path given).
OPTIONS = ("--rate", "--ramp-speed", "--format", "--source-fps", "--latency-ms")
BY_NAME = {c.name: c for c in CASES}
NAMES = [n for group in ISSUE_CASES.values() for n in group]


def test_the_corpus_holds_every_case_the_issue_names():
    assert [n for n in NAMES if n not in BY_NAME] == []


@pytest.mark.parametrize("name", NAMES)
def test_the_issues_case_is_one_line_naming_the_file_or_option(name, tmp_path):
    out = run_case(BY_NAME[name], tmp_path)
    assert out.handled, out.describe()
    line = out.stderr.strip()
    named = [t for t in out.argv if t.startswith(str(tmp_path)) or t in OPTIONS]
    named += [t.split("=")[0] for t in out.argv if "=" in t]  # --policy key=value names the key
    assert any(t in line for t in named), (line, named)

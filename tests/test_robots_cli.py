"""``motion2robot robots`` / ``robots show`` / ``robots init`` through the CLI entry point."""

import pytest

from motion2robot.cli import main
from motion2robot.robot import load_robot
from tests._shared import MENAGERIE, requires_menagerie


@pytest.fixture(autouse=True)
def _fresh_cache():
    load_robot.cache_clear()
    yield
    load_robot.cache_clear()


@requires_menagerie
def test_list_marks_menagerie_robots_available(capsys, monkeypatch):
    monkeypatch.setenv("MENAGERIE_ROOT", str(MENAGERIE))
    assert main(["robots"]) == 0
    out = capsys.readouterr().out
    lines = {ln.split()[0]: ln for ln in out.splitlines() if ln.strip()}
    assert "bundled" in lines["op3"] and " 20 " in lines["op3"]
    for name, dof in (("menagerie:unitree_g1", 29), ("menagerie:unitree_h1", 19)):
        assert "menagerie" in lines[name] and " yes " in lines[name] and f" {dof} " in lines[name]
        assert f"MENAGERIE_ROOT={MENAGERIE}" in lines[name]


def test_list_marks_missing_menagerie_robots_unavailable(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("MENAGERIE_ROOT", str(tmp_path))
    assert main(["robots"]) == 0
    out = capsys.readouterr().out
    line = next(ln for ln in out.splitlines() if ln.startswith("menagerie:unitree_g1"))
    assert " no " in line and "not there" in line
    assert next(ln for ln in out.splitlines() if ln.startswith("op3 "))


def test_show_op3(capsys):
    assert main(["robots", "show", "op3"]) == 0
    out = capsys.readouterr().out
    r = load_robot("op3")
    assert f"{r.mass:.3f} kg" in out and f"{r.height:.3f} m" in out and r.model_hash in out
    assert "SERVO ID" in out and "XM430-W350" in out
    for name in r.joint_names:
        row = next(ln for ln in out.splitlines() if ln.startswith(name + " "))
        i = r.joint_index(name)
        assert f"{r.lower[i]:+.3f}" in row and f"{r.upper[i]:+.3f}" in row
        assert row.split()[-1] == str(r.config.servos.by_joint()[name].id)
    assert "left_wrist" in out and "feet" in out and "scale overrides" in out


@requires_menagerie
def test_show_menagerie_g1(capsys, monkeypatch):
    monkeypatch.setenv("MENAGERIE_ROOT", str(MENAGERIE))
    assert main(["robots", "show", "menagerie:unitree_g1"]) == 0
    out = capsys.readouterr().out
    assert "29 hinges" in out and "33.341 kg" in out and "SERVO ID" not in out
    knee = next(ln for ln in out.splitlines() if ln.startswith("left_knee_joint "))
    # lower/upper in rad and degrees, velocity, torque, kp, nominal
    assert knee.split()[1:] == ["-0.087", "+2.880", "-5.0", "+165.0", "20.00", "139.00", "200", "+0.300"]
    assert "body left_wrist_pitch_link" in out and "left_ankle_roll_link: centre (+0.0350, +0.0000, -0.0350), size 0.170 x 0.060" in out
    assert "top of the model 1.3" in out  # the G1 is about 1.32 m tall


@pytest.mark.parametrize("argv, needle", [
    (["robots", "show", "nao"], "unknown robot 'nao'"),
    (["robots", "show", "menagerie:booster_t1"], "no shipped config"),
    (["robots", "init", "nope.xml", "-o", "x.toml"], "MJCF not found"),
])
def test_errors_are_one_line_exit_2(capsys, argv, needle):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1 and "Traceback" not in err


@requires_menagerie
def test_init_end_to_end(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("MENAGERIE_ROOT", str(MENAGERIE))
    out_toml = tmp_path / "h1.toml"
    assert main(["robots", "init", "menagerie:unitree_h1", "-o", str(out_toml)]) == 0
    out = capsys.readouterr().out
    assert f"wrote {out_toml}" in out and "guessed:" in out and "needs a human look" in out and "CHECK" in out_toml.read_text()
    assert "left_knee_link (by name)" in out
    # refuses to overwrite without --force
    assert main(["robots", "init", "menagerie:unitree_h1", "-o", str(out_toml)]) == 2
    assert "--force" in capsys.readouterr().err
    # the draft shows like any robot
    assert main(["robots", "show", str(out_toml)]) == 0
    shown = capsys.readouterr().out
    assert "19 hinges" in shown and "left_hip_roll_link" in shown
    # and compares with the shipped config
    assert main(["robots", "compare", str(out_toml), "menagerie:unitree_h1"]) == 0
    cmp_out = capsys.readouterr().out
    knee = next(ln for ln in cmp_out.splitlines() if ln.startswith("left_knee "))
    assert knee.split()[1:] == ["left_knee_link", "left_knee_link", "yes", "0.0"]
    assert "left sole: corners differ by at most 0.0 mm" in cmp_out

"""Robot names resolve to configs or fail with one line naming the fix; configs are validated against the model."""

import shutil
from pathlib import Path

import pytest

from motion2robot.errors import RobotConfigError
from motion2robot.robot import load_robot
from motion2robot.robot.resolve import menagerie_available, menagerie_mjcf, resolve, robots_dir
from tests._shared import MENAGERIE, requires_menagerie

HOW = "menagerie:NAME"


@pytest.fixture(autouse=True)
def _fresh_cache():
    load_robot.cache_clear()
    yield
    load_robot.cache_clear()


def _one_line(err) -> str:
    msg = str(err.value)
    assert "\n" not in msg
    return msg


def test_unknown_name_says_which_forms_exist():
    with pytest.raises(RobotConfigError) as e:
        load_robot("nao")
    msg = _one_line(e)
    assert "unknown robot 'nao'" in msg and "op3" in msg and HOW in msg and ".toml beside it" in msg


def test_menagerie_name_without_shipped_config_suggests_init():
    with pytest.raises(RobotConfigError) as e:
        load_robot("menagerie:booster_t1")
    msg = _one_line(e)
    assert "no shipped config" in msg and "menagerie:unitree_g1" in msg
    assert "motion2robot robots init menagerie:booster_t1 -o booster_t1.toml" in msg


def test_mjcf_path_without_toml_suggests_init(tmp_path):
    xml = tmp_path / "bot.xml"
    xml.write_text("<mujoco/>")
    with pytest.raises(RobotConfigError) as e:
        load_robot(str(xml))
    msg = _one_line(e)
    assert "no config bot.toml beside the MJCF" in msg and "robots init" in msg


def test_missing_paths(tmp_path):
    for p, needle in [(tmp_path / "nope.xml", "MJCF not found"), (tmp_path / "nope.toml", "robot config not found"),
                      (tmp_path, "is a directory")]:
        with pytest.raises(RobotConfigError) as e:
            resolve(str(p))
        assert needle in _one_line(e)


def test_offline_menagerie_without_the_robot(tmp_path, monkeypatch):
    """MENAGERIE_ROOT set to a folder without the robot: nothing is downloaded, the error says what to do."""
    monkeypatch.setenv("MENAGERIE_ROOT", str(tmp_path))
    ok, where = menagerie_available("unitree_g1")
    assert not ok and "not there" in where
    with pytest.raises(RobotConfigError) as e:
        load_robot("menagerie:unitree_g1")
    msg = _one_line(e)
    assert "MENAGERIE_ROOT" in msg and str(tmp_path / "unitree_g1") in msg


@requires_menagerie
def test_menagerie_default_entry_point(monkeypatch):
    """Without [model] entry, the registry's default model is used (h1.xml, not unitree_h1.xml)."""
    monkeypatch.setenv("MENAGERIE_ROOT", str(MENAGERIE))
    assert menagerie_mjcf("unitree_h1", None)[0].name == "h1.xml"
    assert menagerie_mjcf("robotis_op3", None)[0].name == "op3.xml"
    with pytest.raises(RobotConfigError) as e:
        menagerie_mjcf("unitree_h1", "h2")
    assert "h1.xml" in _one_line(e) and "entry" in str(e.value)


# -- validation against the model: a copy of the shipped H1 config with one thing broken ------

def _h1_variant(tmp_path: Path, old: str, new: str) -> str:
    text = (robots_dir() / "menagerie" / "unitree_h1.toml").read_text()
    assert old in text
    p = tmp_path / "h1_variant.toml"
    p.write_text(text.replace(old, new, 1))
    return str(p)


@requires_menagerie
@pytest.mark.parametrize("old, new, needle", [
    ('name = "unitree_h1"', 'name = "unitree_h1"\ncolour = "red"', "unknown key(s) colour"),
    ('left_knee = { body = "left_knee_link" }', 'left_knee = { body = "left_knee" }',
     "keypoints.left_knee names body 'left_knee', which the model does not have"),
    ('body = "left_ankle_link"\nsole', 'body = "left_foot"\nsole', "feet.left.body 'left_foot' is not a body"),
    ("[joints.left_knee]\n", "[joints.left_knee]\nrange = [-0.5, 2.0]\n",
     "joints.left_knee.range [-0.5, 2] lies outside the model's range [-0.26, 2.05]"),
    ("left_knee = 0.3", "left_knee = 2.5", "nominal.left_knee = 2.5 rad is outside the joint's range"),
    ("[joints.torso]", "[joints.waist]", "[joints] names waist, not joints of the model"),
    ('torso_body = "torso_link"', 'torso_body = "chest"', "torso_body 'chest' is not a body"),
])
def test_config_errors_against_the_model(tmp_path, monkeypatch, old, new, needle):
    monkeypatch.setenv("MENAGERIE_ROOT", str(MENAGERIE))
    with pytest.raises(RobotConfigError) as e:
        load_robot(_h1_variant(tmp_path, old, new))
    msg = _one_line(e)
    assert needle in msg and "h1_variant.toml" in msg


@requires_menagerie
def test_narrowed_range_is_applied(tmp_path, monkeypatch):
    monkeypatch.setenv("MENAGERIE_ROOT", str(MENAGERIE))
    r = load_robot(_h1_variant(tmp_path, "[joints.left_knee]\n", '[joints.left_knee]\nrange = [0.0, 1.5]\nreason = "test"\n'))
    i = r.joint_index("left_knee")
    assert (r.lower[i], r.upper[i]) == (0.0, 1.5) and r.config.joint("left_knee").reason == "test"


@requires_menagerie
def test_mjcf_path_with_toml_beside_it(tmp_path, monkeypatch):
    """A path to an MJCF loads with the .toml beside it (here: the H1 MJCF copied, its meshes linked, config using mjcf=)."""
    monkeypatch.setenv("MENAGERIE_ROOT", str(MENAGERIE))
    folder = tmp_path / "h1"
    folder.mkdir()
    shutil.copy(MENAGERIE / "unitree_h1" / "h1.xml", folder / "h1.xml")
    (folder / "assets").symlink_to(MENAGERIE / "unitree_h1" / "assets")
    text = (robots_dir() / "menagerie" / "unitree_h1.toml").read_text()
    text = text.replace('menagerie = "unitree_h1"\nentry = "h1"', 'mjcf = "h1.xml"')
    (folder / "h1.toml").write_text(text)
    r = load_robot(str(folder / "h1.xml"))
    assert r.n_joints == 19 and r.source == f"file {folder / 'h1.xml'}"


def test_offline_without_root_and_without_cache(tmp_path, monkeypatch):
    """No MENAGERIE_ROOT, an empty cache and an unreachable archive server: one line naming the ways out."""
    pytest.importorskip("mujoco_menagerie")
    monkeypatch.delenv("MENAGERIE_ROOT", raising=False)
    monkeypatch.setenv("MENAGERIE_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("MENAGERIE_BASE_URL", (tmp_path / "no_server").as_uri())
    ok, where = menagerie_available("unitree_h1")
    assert not ok and "not cached" in where
    with pytest.raises(RobotConfigError) as e:
        load_robot("menagerie:unitree_h1")
    msg = _one_line(e)
    assert "cannot fetch the model" in msg and "set MENAGERIE_ROOT" in msg and ".toml beside it" in msg


def test_a_servo_for_a_joint_the_model_does_not_have_names_the_config(tmp_path):
    """Issue 20: a servo ID for a joint that does not exist was accepted by 'robots show' and
    'retarget'; 'stream' then blamed the motion and suggested retargeting it."""
    op3 = robots_dir() / "op3"
    text = (op3 / "op3.toml").read_text().replace('mjcf = "op3.xml"', f'mjcf = "{op3 / "op3.xml"}"')
    assert "r_sho_pitch = 1" in text
    p = tmp_path / "bot.toml"
    p.write_text(text.replace("r_sho_pitch = 1", "r_tail = 1"))
    with pytest.raises(RobotConfigError) as e:
        load_robot(str(p))
    msg = _one_line(e)
    assert msg.startswith(f"{p}: [servos.ids] names r_tail, not hinge joints of the model") and "r_sho_pitch" in msg

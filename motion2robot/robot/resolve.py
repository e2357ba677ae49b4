"""Where a robot name points: ``op3`` (bundled) | ``menagerie:NAME`` | a path to an MJCF or TOML.

Menagerie models come from ``$MENAGERIE_ROOT/NAME`` when that is set, else through the optional
``mujoco-menagerie`` package (its cache, or a download on a machine with internet, with
progress shown). Nothing is downloaded when ``MENAGERIE_ROOT`` is set.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from motion2robot.errors import RobotConfigError

MENAGERIE_PREFIX = "menagerie:"
_HOW = "use 'op3' (bundled), 'menagerie:NAME' (e.g. menagerie:unitree_g1) or a path to an MJCF with a .toml beside it"


@dataclass(frozen=True)
class RobotSource:
    """A resolved robot: its config file, its MJCF, and a description of where both came from."""

    name: str
    config_path: Path
    mjcf_path: Path | None  # None until the config names it (bundled/path robots)
    origin: str


def robots_dir() -> Path:
    """The folder of robot descriptions shipped with the package (``robots/`` in the source tree)."""
    return Path(str(resources.files("motion2robot.robots")))


def bundled_names() -> list[str]:
    """Bundled robots: ``robots/<name>/<name>.toml``."""
    root = robots_dir()
    return sorted(p.name for p in root.iterdir() if p.is_dir() and (p / f"{p.name}.toml").is_file())


def menagerie_config_names() -> list[str]:
    """Menagerie robots with a shipped config: ``robots/menagerie/<NAME>.toml``."""
    d = robots_dir() / "menagerie"
    return sorted(p.stem for p in d.glob("*.toml")) if d.is_dir() else []


def menagerie_root() -> Path | None:
    root = os.environ.get("MENAGERIE_ROOT")
    return Path(root) if root else None


def menagerie_available(name: str) -> tuple[bool, str]:
    """Whether menagerie robot ``name`` can be loaded offline now, and from where (for listings)."""
    root = menagerie_root()
    if root is not None:
        ok = (root / name).is_dir()
        return ok, f"MENAGERIE_ROOT={root}" + ("" if ok else " (not there)")
    try:
        import mujoco_menagerie
    except ImportError:
        return False, "needs MENAGERIE_ROOT or 'pip install motion2robot[menagerie]'"
    try:
        robot = mujoco_menagerie.get(name)
        cache = mujoco_menagerie.Cache()
        if cache.is_cached(robot):
            return True, f"menagerie cache {cache.dir}"
        return False, "not cached; downloads on first use (needs internet)"
    except Exception as err:  # unknown name or registry trouble
        return False, f"mujoco-menagerie: {err}"


def _default_entry(name: str, folder: Path) -> str:
    """The robot entry point of a menagerie folder when the config names none: the registry's
    ``default_model`` if ``mujoco-menagerie`` knows the robot and the folder has it, else
    ``NAME.xml``, else the only MJCF that is not a scene."""
    try:
        import mujoco_menagerie

        entry = mujoco_menagerie.get(name).default_model
        if (folder / f"{entry}.xml").is_file():
            return entry
    except Exception:  # package absent or robot not in its registry
        pass
    if (folder / f"{name}.xml").is_file():
        return name
    cands = [p.stem for p in folder.glob("*.xml") if not p.stem.startswith("scene")]
    return cands[0] if len(cands) == 1 else name


def menagerie_mjcf(name: str, entry: str | None) -> tuple[Path, str]:
    """Path of a menagerie robot's MJCF and a description of its origin."""
    root = menagerie_root()
    if root is not None:
        folder = root / name
        if not folder.is_dir():
            raise RobotConfigError(f"menagerie:{name}: no folder {folder} under MENAGERIE_ROOT; check MENAGERIE_ROOT or the robot name")
        xml = folder / f"{entry or _default_entry(name, folder)}.xml"
        if not xml.is_file():
            cands = sorted(p.name for p in folder.glob("*.xml"))
            raise RobotConfigError(f"menagerie:{name}: {xml.name} not found in {folder}; set [model] entry to one of {', '.join(cands)}")
        return xml, f"menagerie (MENAGERIE_ROOT={root})"
    try:
        import mujoco_menagerie
    except ImportError:
        raise RobotConfigError(
            f"menagerie:{name}: MENAGERIE_ROOT is not set and mujoco-menagerie is not installed; "
            "set MENAGERIE_ROOT to a Menagerie checkout or 'pip install motion2robot[menagerie]'") from None
    try:
        robot = mujoco_menagerie.get(name)
        xml = robot.xml(entry)
    except Exception as err:
        raise RobotConfigError(
            f"menagerie:{name}: cannot fetch the model ({type(err).__name__}: {err}); offline, set "
            "MENAGERIE_ROOT to a Menagerie checkout, or give a path to an MJCF with a .toml beside it") from err
    return Path(xml), "menagerie (mujoco-menagerie cache)"


def resolve(name: str) -> RobotSource:
    """Find the config (and where known the MJCF) for a robot name; one-line errors say which form to use."""
    name = str(name).strip()
    if not name:
        raise RobotConfigError(f"empty robot name; {_HOW}")
    if name.startswith(MENAGERIE_PREFIX):
        mname = name[len(MENAGERIE_PREFIX):]
        cfg = robots_dir() / "menagerie" / f"{mname}.toml"
        if not cfg.is_file():
            known = ", ".join(MENAGERIE_PREFIX + n for n in menagerie_config_names())
            raise RobotConfigError(
                f"{name}: no shipped config for this Menagerie robot (shipped: {known}); draft one with "
                f"'motion2robot robots init {name} -o {mname}.toml' and pass that path")
        return RobotSource(name, cfg, None, "menagerie")
    if name in bundled_names():
        return RobotSource(name, robots_dir() / name / f"{name}.toml", None, "bundled")
    p = Path(name).expanduser()
    if p.suffix.lower() in (".xml", ".toml") or p.exists():
        if p.is_dir():
            raise RobotConfigError(f"{p}: is a directory; {_HOW}")
        if p.suffix.lower() == ".toml":
            if not p.is_file():
                raise RobotConfigError(f"{p}: robot config not found; {_HOW}")
            return RobotSource(str(p), p, None, f"file {p}")
        if not p.is_file():
            raise RobotConfigError(f"{p}: MJCF not found; {_HOW}")
        cfg = p.with_suffix(".toml")
        if not cfg.is_file():
            raise RobotConfigError(
                f"{p}: no config {cfg.name} beside the MJCF; draft one with "
                f"'motion2robot robots init {p} -o {cfg}' and check it")
        return RobotSource(str(p), cfg, p, f"file {p}")
    raise RobotConfigError(f"unknown robot {name!r} (bundled: {', '.join(bundled_names())}); {_HOW}")

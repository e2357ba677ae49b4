"""Package layout: the top-level data folders ``robots/`` and ``sim/`` are shipped inside the
wheel as the resource packages ``motion2robot.robots`` and ``motion2robot.worlds``, so robots load
from the installed package (``importlib.resources``), never from the source tree.
Everything else lives in pyproject.toml."""
from setuptools import find_packages, setup

setup(
    packages=find_packages(include=["motion2robot", "motion2robot.*"])
    + ["motion2robot.robots", "motion2robot.worlds"],
    package_dir={"motion2robot.robots": "robots", "motion2robot.worlds": "sim"},
    package_data={
        "motion2robot": ["data/*"],
        "motion2robot.robots": ["*.toml", "*/*.toml", "*/*.xml", "*/*.md"],
        "motion2robot.worlds": ["*.xml", "*.md"],
    },
    include_package_data=False,
)

"""The installed project is the checkout: every package folder is listed for the wheel.

A package missing from ``[tool.setuptools] packages`` works in an editable
install and is absent after a plain ``pip install .`` (as ``planner.io.hddl``
once was), so CI, which installs that way, fails where a developer's checkout
passes.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

tomllib = pytest.importorskip("tomllib")  # Python 3.11+

REPO = Path(__file__).resolve().parents[1]


def test_every_package_folder_is_listed_in_pyproject():
    setup = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(setup["packages"])
    found = {".".join(init.parent.relative_to(REPO).parts)
             for top in ("userfiles", "planner", "sim", "shary")
             for init in (REPO / top).rglob("__init__.py")}
    assert found - listed == set(), "add these to [tool.setuptools] packages"


def test_no_file_names_a_folder_of_one_machine():
    """A path under ``/work`` or a home folder exists on one machine: the checkout is read
    relative to itself, and the external suites through ``tests/suites.py``."""
    machine = re.compile(r"(?<![\w.:/])/(?:work|home/\w+|Users/\w+|root)/")
    found = [f"{path.relative_to(REPO)}:{number}: {line.strip()}"
             for top in ("tests", "benchmarks", "shary", "sim", "planner", "userfiles", "docs")
             for path in sorted((REPO / top).rglob("*"))
             if path.suffix in (".py", ".md", ".yaml", ".json", ".txt") and path.is_file()
             and path.stat().st_size < 1_000_000
             for number, line in enumerate(path.read_text(encoding="utf-8", errors="replace")
                                           .splitlines(), 1)
             if machine.search(line)]
    assert found == [], "\n".join(found)


def test_the_ros_extra_builds_the_interface_package_of_this_checkout():
    """``pip install '.[ros]'`` builds ``ros/shary_interfaces`` from the checkout it was
    run in (setup.py gives its absolute address; a relative one is not a requirement)."""
    from importlib.metadata import requires
    from urllib.parse import unquote, urlparse

    from packaging.requirements import Requirement

    wanted = [Requirement(r) for r in requires("shary") or []
              if r.startswith("shary-ros-interfaces")]
    assert [str(r.marker) for r in wanted] == ['extra == "ros"']
    folder = Path(unquote(urlparse(wanted[0].url).path))
    assert folder == REPO / "ros" / "shary_interfaces"
    assert (folder / "package.xml").is_file() and (folder / "pyproject.toml").is_file()

"""The installed project is the checkout: every package folder is listed for the wheel.

A package missing from ``[tool.setuptools] packages`` works in an editable
install and is absent after a plain ``pip install .`` (as ``planner.hddl``
once was), so CI, which installs that way, fails where a developer's checkout
passes.
"""

from __future__ import annotations

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

"""Where the built-in YAML lives once installed.

The top-level folders of the repository (``schemes/`` …) are installed as
sub-packages of this one (see ``[tool.setuptools.package-dir]`` in
``pyproject.toml``), so they are found after a plain ``pip install .`` as well
as in an editable checkout.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path


def folder(kind: str) -> Path:
    """The folder of built-in files of one kind (``schemes`` …).

    Installed, it is the package ``shary.builtin.KIND``; when ``shary`` is
    imported straight from a source checkout (tests run from its top), that
    package is not importable and the checkout's own folder is used.
    """
    try:
        return Path(str(resources.files(f"shary.builtin.{kind}")))
    except ModuleNotFoundError:
        return Path(__file__).resolve().parents[2] / kind


def files(kind: str) -> list[Path]:
    """Every built-in YAML file of one kind, sorted by name."""
    return sorted(folder(kind).glob("*.yaml"))


def find(kind: str, name: str) -> Path | None:
    """The built-in file ``NAME.yaml`` of one kind, if there is one."""
    path = folder(kind) / f"{name}.yaml"
    return path if path.is_file() else None

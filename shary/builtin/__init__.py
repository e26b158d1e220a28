"""Where the built-in YAML lives.

The top-level folders of the repository (``schemes/`` …) are installed as
sub-folders of this package (see ``[tool.setuptools.package-dir]`` in
``pyproject.toml``), so a plain ``pip install .`` carries them.  In a source
checkout (editable install, or tests run from the top of the repository) they
are the checkout's own folders.
"""

from __future__ import annotations

from pathlib import Path

_HERE = Path(__file__).resolve().parent


def folder(kind: str) -> Path:
    """The folder of built-in files of one kind (``schemes`` …)."""
    installed = _HERE / kind
    return installed if installed.is_dir() else _HERE.parents[1] / kind


def files(kind: str) -> list[Path]:
    """Every built-in YAML file of one kind, sorted by name."""
    return sorted(folder(kind).glob("*.yaml"))


def find(kind: str, name: str) -> Path | None:
    """The built-in file ``NAME.yaml`` of one kind, if there is one."""
    path = folder(kind) / f"{name}.yaml"
    return path if path.is_file() else None

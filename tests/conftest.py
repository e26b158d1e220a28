"""Shared helpers for the tests: write a file, run the CLI in-process."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import pytest
from rosfixtures import ros_domain, spawn  # noqa: F401 -- the ROS tests' fixtures

from shary.cli import main

pytest_plugins = ["suites"]
"""Whether an external suite is there is asked as each test starts (tests/suites.py)."""

REPO = Path(__file__).resolve().parents[1]
PROBLEM_LINE = re.compile(r"^(?P<file>.+):(?P<line>\d+):(?P<col>\d+): error: (?P<message>.+)$")


@pytest.fixture
def write(tmp_path: Path):
    """Write dedented text (or bytes) to a file under tmp_path and return its path."""
    def _write(name: str, content: str | bytes) -> Path:
        path = tmp_path / name
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(textwrap.dedent(content), encoding="utf-8")
        return path
    return _write


@pytest.fixture
def shary(capsys):
    """Run ``shary ARGS`` in-process; return (status, stdout, stderr)."""
    def _run(*args: str) -> tuple[int, str, str]:
        status = main([str(a) for a in args])
        captured = capsys.readouterr()
        return status, captured.out, captured.err
    return _run


def problems(stderr: str) -> list[re.Match]:
    """The FILE:LINE:COL problem lines of a command's standard error."""
    found = [PROBLEM_LINE.match(line) for line in stderr.splitlines()]
    return [m for m in found if m]

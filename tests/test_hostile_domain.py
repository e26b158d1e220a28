"""Hostile planning domains and problems (YAML): refused by ``shary validate`` and
``shary plan``, never a RecursionError or a traceback."""

from __future__ import annotations

from pathlib import Path

import pytest
from hostile import assert_refused, run_inprocess, run_subprocess
from hostile_files import blamable, corpus, expected

CASES = corpus("domain")
DOMAINS = [p for p in CASES if not p.stem.startswith("problem-")]


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_validate_refuses(path: Path) -> None:
    assert_refused(run_inprocess("validate", path), *blamable(path), message=expected(path))


def test_plan_refuses_nan_budget() -> None:
    path = next(p for p in CASES if p.stem == "problem-nan-budget")
    outcome = run_inprocess("plan", "living-room", path)
    assert_refused(outcome, path, message=expected(path))


@pytest.mark.parametrize("name", ["deep-not", "deep-parentheses"])
def test_deep_expressions_in_a_child(name: str) -> None:
    """Measured in a child process: the stack and the memory are its own."""
    path = next(p for p in DOMAINS if p.stem == name)
    assert_refused(run_subprocess("validate", path), path, message=expected(path))

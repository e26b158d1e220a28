"""Hostile seam-welding scenario files: refused by ``shary validate`` and ``shary run``
with the rule of tests/hostile.py (the team file they name is checked with them)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hostile import assert_refused, run_inprocess, run_subprocess
from hostile_files import blamable, corpus, expected

CASES = corpus("weld")


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_validate_refuses(path: Path) -> None:
    assert_refused(run_inprocess("validate", path), *blamable(path), message=expected(path))


def test_run_refuses_before_building_the_site(tmp_path: Path) -> None:
    path = next(p for p in CASES if p.stem == "welded-unmounted")
    outcome = run_subprocess("run", path, "--out", tmp_path / "out")
    assert_refused(outcome, path, message=expected(path))
    assert not (tmp_path / "out" / "log.sqlite").exists()

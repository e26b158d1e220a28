"""Hostile acts files: refused by ``shary validate`` with the rule of tests/hostile.py."""

from __future__ import annotations

from pathlib import Path

import pytest
from hostile import assert_refused, run_inprocess
from hostile_files import blamable, corpus, expected

CASES = corpus("acts")


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_validate_refuses(path: Path) -> None:
    assert_refused(run_inprocess("validate", path), *blamable(path), message=expected(path))

"""Hostile action model files: refused by ``shary validate`` with the rule of tests/hostile.py."""

from __future__ import annotations

from pathlib import Path

import pytest
from hostile import assert_refused, run_inprocess
from hostile_files import blamable, corpus, expected

CASES = corpus("action-models")


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_validate_refuses(path: Path) -> None:
    assert_refused(run_inprocess("validate", path), *blamable(path), message=expected(path))


def test_a_file_of_ten_thousand_actions_is_refused_at_the_limit(tmp_path: Path) -> None:
    path = tmp_path / "many.yaml"
    path.write_text("action-models: many\nhuman:\n" + "".join(
        f"  a{i}: {{agent: Human, necessary: ['isOn(Human, Human)']}}\n" for i in range(10_000)))
    assert_refused(run_inprocess("validate", path), path, message="more than 200|maxProperties")

"""Hostile scenarios: refused by ``shary validate`` (and by ``shary run`` before any run)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hostile import HOSTILE, assert_refused, run_inprocess, run_subprocess
from hostile_files import blamable, corpus, expected

CASES = corpus("scenario")


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_validate_refuses(path: Path) -> None:
    assert_refused(run_inprocess("validate", path), *blamable(path), message=expected(path))


@pytest.mark.parametrize("name", ["nan-within", "fault-times", "unknown-partner",
                                  "goal-million-hours", "recipes-etc-passwd",
                                  "atomic-without-executor", "expect-unknown-predicate",
                                  "expect-unknown-thing", "goal-after-timeout",
                                  "task-starts-itself"])
def test_run_refuses_before_running(name: str, tmp_path: Path) -> None:
    """These validated and then hung, failed or read a system file at run time."""
    path = next(p for p in CASES if p.stem == name)
    outcome = run_inprocess("run", path, "--out", tmp_path / "out", "--quiet")
    assert_refused(outcome, *blamable(path), message=expected(path))
    assert not (tmp_path / "out" / "log.sqlite").exists()


def test_a_task_that_nests_itself_at_run_time_is_stopped_at_its_recipe(tmp_path: Path) -> None:
    """A valid file (its recipe's condition could be false) that nests its task without end
    once run: before, ``shary run`` ended in "maximum recursion depth exceeded"."""
    path = HOSTILE / "scenario" / "run" / "task-nests-itself-when.yaml"
    assert run_inprocess("validate", path).status == 0
    outcome = run_inprocess("run", path, "--out", tmp_path / "out", "--quiet")
    assert_refused(outcome, path.parent / "recipes-nest-when.yaml", message=expected(path))


def test_system_file_never_quoted() -> None:
    path = next(p for p in CASES if p.stem == "recipes-etc-passwd")
    outcome = run_inprocess("validate", path)
    assert "root:" not in outcome.err + outcome.out
    assert "/etc/passwd:" not in outcome.err


def test_ten_thousand_people(tmp_path: Path) -> None:
    """Big but meaningless: refused at the 'people' key, with the limit named, in time."""
    people = "".join(f"  p{i}: {{at: sofa-seat, profile: cooperative}}\n" for i in range(10_000))
    path = tmp_path / "crowd.yaml"
    path.write_text(f"scenario: crowd\npeople:\n{people}expect: {{acts: [ASK-TASK]}}\n")
    outcome = run_subprocess("validate", path)
    assert_refused(outcome, path, message=r"more than 50 entries: too many \(the limit is 50\)")
    print(f"10,000 people: refused in {outcome.seconds:.2f} s, {outcome.peak_mb:.0f} MB")


def test_fifty_people_validate(tmp_path: Path) -> None:
    """At the limit, the scenario is read in time (a named profile is read once)."""
    people = "".join(f"  p{i}: {{at: sofa-seat, profile: cooperative}}\n" for i in range(50))
    path = tmp_path / "crowd.yaml"
    path.write_text(f"scenario: crowd\npeople:\n{people}expect: {{acts: [ASK-TASK]}}\n")
    outcome = run_inprocess("validate", path)
    assert outcome.status == 0, outcome.err

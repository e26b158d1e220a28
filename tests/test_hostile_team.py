"""Hostile team files: refused by ``shary validate`` with the rule of tests/hostile.py.

The corpus is tests/hostile/team/; the inputs too big for git (the most tasks a goal may
have, in a chain that each respawn the first, or in a cycle; more than that) are generated
here."""

from __future__ import annotations

from pathlib import Path

import pytest
from hostile import HOSTILE, assert_refused, run_inprocess, run_subprocess
from hostile_files import blamable, corpus, expected

CASES = corpus("team")
RECIPES = HOSTILE / "team" / "deps" / "seam-recipes.yaml"


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_validate_refuses(path: Path) -> None:
    assert_refused(run_inprocess("validate", path), *blamable(path), message=expected(path))


def _chain(tmp_path: Path, count: int, *, cycle: bool) -> Path:
    (tmp_path / "seam-recipes.yaml").write_text(RECIPES.read_text("utf-8"), "utf-8")
    lines = ["team: big", "recipes: [seam-recipes.yaml]", "agents:",
             "  R: {kind: robot, skills: [weld-seam]}", "goal:", "  tasks:"]
    for i in range(count):
        after = f"t{i - 1}" if i else (f"t{count - 1}" if cycle else None)
        extra = f", after: [{after}]" if after else ""
        respawn = ", respawn: t0" if i and not cycle else ""
        lines.append(f"    t{i}: {{do: weld-seam, with: {{seam: s{i}}}{extra}{respawn}}}")
    if not cycle:  # one wrong respawn at the end, so that the file is refused
        lines.append(f"    late: {{do: weld-seam, with: {{seam: x}}, respawn: t{count - 1}}}")
    path = tmp_path / "big-team.yaml"
    path.write_text("\n".join(lines) + "\n", "utf-8")
    return path


MOST_TASKS = 2000
"""The schema's bound on a goal's tasks."""


def test_a_cycle_through_the_most_tasks(tmp_path: Path) -> None:
    path = _chain(tmp_path, MOST_TASKS, cycle=True)
    assert_refused(run_subprocess("validate", path), path, message="in a cycle: t0 -> ")


def test_the_most_tasks_each_respawning_the_first(tmp_path: Path) -> None:
    path = _chain(tmp_path, MOST_TASKS - 1, cycle=False)
    assert_refused(run_subprocess("validate", path), path,
                   message="late can only respawn a task it comes after")


def test_more_than_the_most_tasks(tmp_path: Path) -> None:
    path = _chain(tmp_path, 5 * MOST_TASKS // 2, cycle=True)  # under the size limit
    assert_refused(run_subprocess("validate", path), path, message="2000")

"""Hostile searches: recursive and explosive domains answer "search budget exhausted".

These files are not wrong (a recursive method is legal), so ``shary plan``
does not refuse them with exit status 2: it answers as for any problem
without a plan, exit status 1, and says which budget ran out and how to raise
it, within the hostile-input limits (10 s, 500 MB, measured in a child).
Each problem sets a time budget of a day: only the depth and node budgets
stand between it and the machine's memory.
"""

from __future__ import annotations

import json

import pytest
from hostile import HOSTILE, MAX_MB, MAX_SECONDS, Outcome, run_subprocess

CORPUS = HOSTILE / "search"
CASES = {
    # name: (command-line files, the budget that must be named)
    "recursive": (["recursive.domain.yaml", "recursive.problem.yaml"], "depth"),
    "explosive": (["explosive.domain.yaml", "explosive.problem.yaml"], "node"),
    "branching": (["branching.domain.yaml", "branching.problem.yaml"], "node"),
    # HDDL's first-plan search sees the recursion come back to a state it searched.
    "recursive-hddl": (["--hddl", "recursive-domain.hddl", "recursive.hddl"], None),
}


def _assert_exhausted(outcome: Outcome, budget: str | None) -> None:
    where = f"\n--- stdout ---\n{outcome.out[-2000:]}\n--- stderr ---\n{outcome.err[-2000:]}"
    assert "Traceback" not in outcome.out + outcome.err, where
    assert outcome.status == 1, f"exit status {outcome.status}, not 1 (no plan){where}"
    if budget is None:
        assert "in this very state (a loop)" in outcome.out, where
    else:
        assert "search budget exhausted" in outcome.out, where
        assert f"{budget} budget" in outcome.out, where
        assert f"--max-{'depth' if budget == 'depth' else 'nodes'}" in outcome.out, where
    assert outcome.seconds < MAX_SECONDS, f"took {outcome.seconds:.1f} s{where}"
    assert outcome.peak_mb < MAX_MB, f"needed {outcome.peak_mb:.0f} MB{where}"


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_runaway_search_answers_which_budget_ran_out(case: str) -> None:
    files, budget = CASES[case]  # budget None: no budget runs out, the loop is seen
    argv = [f if f.startswith("--") else CORPUS / f for f in files]
    _assert_exhausted(run_subprocess("plan", *argv), budget)


def test_the_budgets_can_be_raised_and_lowered_from_the_command_line() -> None:
    files = [CORPUS / "recursive.domain.yaml", CORPUS / "recursive.problem.yaml"]
    shallow = run_subprocess("plan", *files, "--max-depth", "50", "--json")
    assert shallow.status == 1, shallow.err
    answer = json.loads(shallow.out)
    assert answer["found"] is False and answer["complete"] is False
    assert "depth budget (50 nested tasks)" in answer["exhausted"]
    few = run_subprocess("plan", *files, "--max-nodes", "1000", "--max-depth", "100000",
                         "--json")
    assert "node budget (1,000 nodes" in json.loads(few.out)["exhausted"]


def test_every_corpus_file_is_used() -> None:
    used = {f for files, _ in CASES.values() for f in files if not f.startswith("--")}
    assert used == {p.name for p in CORPUS.iterdir()}

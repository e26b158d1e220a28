"""The planner's behaviour pinned: plan, score, expansions, plans found and actions
applied, for a few problems and each way of searching them.

The search's step and bounds are optimised for speed (docs/benchmarks.md); an
optimisation must leave what the search does exactly as it was.  A change here is
a change of behaviour: a tighter admissible bound may lower the expansions (never
change the plan or its score), anything else is a bug.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from planner import load_domain, load_problem
from planner.search.branchbound import Result, Search

ROOT = Path(__file__).resolve().parents[1]
sys.path.append(str(ROOT / "benchmarks"))

from livingroom import clean_up  # noqa: E402


def _print(result: Result) -> tuple:
    assert result.plan is not None
    return (result.expansions, result.plans_found, result.applied, result.plan.score)


def _actions(result: Result) -> list[str]:
    assert result.plan is not None
    return [" ".join((a.name, *a.args)) for a in result.plan.actions]


# (bottles, agents): best, without lookahead, first plan, best without rules; each
# (expansions, plans found, actions applied, score)
LIVING = {
    (3, 2): ((382, 5, 144, 23.5), (803, 5, 269, 23.5), (34, 1, 13, 31.5), (343, 2, 132, 20.0)),
    (4, 2): ((3001, 38, 1160, 46.0), (5187, 38, 1741, 46.0), (50, 1, 19, 66.5),
             (1104, 3, 464, 32.0)),
    (2, 3): ((413, 8, 184, 21.5), (830, 8, 316, 21.5), (25, 1, 9, 27.5), (189, 1, 84, 16.0)),
    (4, 1): ((460, 7, 171, 20.0), (1083, 7, 355, 20.0), (37, 1, 16, 32.0), (376, 3, 141, 20.0)),
}

BEST_4_2 = [
    "Move jido coffee-area", "Pick jido yellow-bottle coffee-table", "Move jido side-area",
    "PutDown jido yellow-bottle side-table", "Pick alice red-bottle sofa",
    "Move alice side-area", "Give alice jido red-bottle", "Move jido coffee-area",
    "PutDown jido red-bottle coffee-table", "Move jido side-area",
    "Pick jido green-bottle side-table", "Move jido coffee-area",
    "PutDown jido green-bottle coffee-table", "Move alice coffee-area",
    "Pick alice blue-bottle coffee-table", "Give alice jido blue-bottle",
    "Move jido side-area", "PutDown jido blue-bottle side-table"]


@pytest.mark.parametrize("size", sorted(LIVING))
def test_the_living_room_searches_are_pinned(size: tuple[int, int]) -> None:
    best, plain, first, bare = LIVING[size]
    problem = clean_up(*size)
    assert _print(Search(problem).run(120_000)) == best
    assert _print(Search(problem, lookahead=False).run(120_000)) == plain
    assert _print(Search(problem).run(120_000, first=True)) == first
    assert _print(Search(clean_up(*size, rules=False)).run(120_000)) == bare


def test_the_best_plan_itself_is_pinned() -> None:
    assert _actions(Search(clean_up(4, 2)).run(120_000)) == BEST_4_2


@pytest.mark.parametrize(("name", "domain", "pinned", "actions"), [
    ("serve-drink", "living-room", (54, 1, 23, 8.0),
     ["Move jido coffee-area", "Pick jido orange-bottle coffee-table",
      "Move jido sofa-area", "Give jido alice orange-bottle"]),
    ("clean-up-unreachable", "living-room", (35, 1, 14, 38.0),
     ["Move alice coffee-area", "Pick alice yellow-bottle coffee-table", "Move alice base",
      "Give alice jido yellow-bottle", "Move jido trash-area",
      "Dump jido yellow-bottle trash"]),
    ("fig6", "fig6", (299, 14, 138, 14.5),
     ["Open jido cupboard", "Pickup jido glass cupboard", "Close jido cupboard",
      "Move jido living", "Give jido human glass", "Move human dining",
      "Pickup human bottle table", "Move human living", "Sit human sofa"]),
])
def test_the_built_in_problems_are_pinned(name: str, domain: str, pinned: tuple,
                                          actions: list[str]) -> None:
    loaded = load_domain(domain)
    problem = load_problem(ROOT / "planner" / "problems" / f"{name}.yaml", loaded)
    if domain == "living-room":
        problem.select_rules(list(loaded.rules))
    result = Search(problem).run(120_000)
    assert _print(result) == pinned
    assert _actions(result) == actions

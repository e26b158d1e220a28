"""The branch and bound's floor and lookahead are admissible: the same best score as a
search that prunes nothing, on small instances where that search is exhaustive."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from planner import load_domain, load_problem, validate
from planner.model.state import State
from planner.search.bound import RemainingCost, conjuncts
from planner.search.branchbound import Search

ROOT = Path(__file__).resolve().parents[1]
sys.path.append(str(ROOT / "benchmarks"))

from livingroom import clean_up  # noqa: E402


def _unpruned(problem) -> Search:  # type: ignore[no-untyped-def]
    """A search whose partial plans all have a floor of 0: nothing is pruned before it
    is complete (so it evaluates every plan)."""
    search = Search(problem, lookahead=False)
    stepper = search.stepper  # its steps are compiled on first use: after these
    stepper.links, stepper.waits, stepper.duration_rate, stepper.timed = [], [], 0.0, False
    search.decomposition_floor = {}
    search.evaluator.step_rate = lambda kind: 0.0  # type: ignore[method-assign]
    return search


def _best(search: Search) -> tuple[float, int]:
    result = search.run(120_000)
    assert result.complete and result.plan is not None
    assert validate(search.problem, result.plan) == []
    return result.plan.score, result.plans_found


@pytest.mark.parametrize(("bottles", "agents"),
                         [(1, 1), (2, 1), (1, 2), (2, 2), (3, 2), (2, 3), (3, 3)])
def test_the_proven_best_is_the_exhaustive_searchs_best(bottles: int, agents: int) -> None:
    problem = clean_up(bottles, agents)
    exhaustive, evaluated = _best(_unpruned(problem))
    bounded, found = _best(Search(problem))
    assert bounded == pytest.approx(exhaustive)
    assert found <= evaluated


@pytest.mark.parametrize("name", ["clean-up", "clean-up-unreachable", "serve-drink"])
def test_the_built_in_problems_keep_their_best(name: str) -> None:
    domain = load_domain("living-room")
    problem = load_problem(ROOT / "planner" / "problems" / f"{name}.yaml", domain)
    problem.select_rules(list(domain.rules))
    assert _best(Search(problem))[0] == pytest.approx(_best(_unpruned(problem))[0])


def test_fig6_keeps_its_best() -> None:
    problem = load_problem(ROOT / "planner" / "problems" / "fig6.yaml", load_domain("fig6"))
    assert _best(Search(problem))[0] == pytest.approx(_best(_unpruned(problem))[0])


@pytest.mark.parametrize(("bottles", "agents"), [(2, 2), (3, 2)])
def test_criteria_weighed_by_ahp_keep_their_best(bottles: int, agents: int) -> None:
    """With AHP weights, the floor counts effort, the makespan and the rules by their
    weights."""
    problem = clean_up(bottles, agents)
    problem.weights = {"cost": 0.2, "duration": 0.3, "human-effort": 0.2,
                       "robot-effort": 0.05, "rules": 0.15, "joint-actions": 0.1}
    problem.scale = {"duration": 10.0}
    assert _best(Search(problem))[0] == pytest.approx(_best(_unpruned(problem))[0])


def test_the_lookahead_sees_what_a_bottle_out_of_reach_costs() -> None:
    """Alone, the bottle out of Jido's reach costs Alice's pick and her hand-over, more
    than one within reach; and the bound never exceeds the best plan's cost."""
    problem = clean_up(2, 2, rules=False)
    bound = RemainingCost(problem)
    state = State(dict(problem.initial))
    alone = [bound.bound(((name, args, 0), None), state) for name, args in problem.tasks]
    assert alone[1] > alone[0] > 0
    agenda = None
    for name, args in reversed(problem.tasks):
        agenda = ((name, args, 0), agenda)
    best = Search(problem).run(60_000).plan
    assert best is not None
    assert bound.bound(agenda, state) <= best.criteria["cost"]


def test_conditions_split_at_their_top_level_and() -> None:
    assert conjuncts('a.x == b and (c or d) and e.k == "and"') == [
        "a.x == b", "(c or d)", 'e.k == "and"']
    assert conjuncts("a and b or c") == ["a and b or c"]


def test_the_benchmark_reports_its_figures_on_a_tiny_size() -> None:
    pytest.importorskip("gtpyhop", reason="GTPyhop comes with the bench extra")
    import json
    import subprocess

    run = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "planner.py"), "--json",
                          "--bottles", "2", "--agents", "2", "--runs", "1", "--limit", "20"],
                         capture_output=True, text=True, timeout=300, check=True)
    figures = json.loads(run.stdout.strip().splitlines()[-1])
    assert figures["size"] == [2, 2] and figures["sizes"] == 4 and figures["proven"] == 4
    assert figures["first_plan_actions"] == 8 and figures["same_first_plans"] == 4
    assert figures["proven_best_score"] == 21.5
    for name in ("first_plan_ms", "proven_best_ms", "actions_per_s", "gtpyhop_first_plan_ms"):
        assert figures[name] > 0

"""Restarts of the best-first search with shuffled ties (planner/search/restarts.py): where the
estimate is flat, the file order is the whole search, and another order finds the plan."""

from __future__ import annotations

import pytest

from planner import load_hddl, plan, validate
from planner.search import restarts
from planner.search.progression import best_first

# Twenty items to pick from; wandering ends only for a good item, and only once the bit
# b0 is set: a bad item's walk goes through every set of bits before it fails, and all
# of it looks as cheap as a good item's (the task stack's least work is the same).
WALKS = """\
(define (domain walks) (:requirements :typing :hierarchy :negative-preconditions)
  (:types item bit)
  (:constants b0 - bit)
  (:predicates (good ?x - item) (set ?b - bit))
  (:task pick :parameters ())
  (:task wander :parameters (?x - item))
  (:method take :parameters (?x - item) :task (pick) :ordered-subtasks (and (wander ?x)))
  (:method arrive :parameters (?x - item) :task (wander ?x)
    :precondition (and (good ?x) (set b0)) :ordered-subtasks ())
  (:method step :parameters (?x - item ?b - bit) :task (wander ?x)
    :precondition (not (set ?b)) :ordered-subtasks (and (flip ?b) (wander ?x)))
  (:action flip :parameters (?b - bit) :precondition (not (set ?b)) :effect (set ?b)))
"""


def _walks(good: range) -> str:
    items = " ".join(f"x{i:02d}" for i in range(20))
    bits = " ".join(f"b{i}" for i in range(1, 8))
    facts = " ".join(f"(good x{i:02d})" for i in good)
    return (f"(define (problem p) (:domain walks) (:objects {items} - item {bits} - bit)\n"
            f"  (:htn :ordered-subtasks (and (pick)))\n  (:init {facts}))\n")


@pytest.fixture
def short_runs(monkeypatch):
    monkeypatch.setattr(restarts, "RESTART_NODES", 500)


def test_restarts_find_the_plan_the_file_order_leaves_for_last(write, short_runs):
    # In file order the search walks the bad items x00 to x12 to the end first
    # (some 27,000 nodes); shuffled, a run soon meets a good one.
    problem = load_hddl(write("d.hddl", WALKS), write("p.hddl", _walks(range(13, 18))))
    assert best_first(problem, 60_000, max_nodes=5_000).plan is None
    result = restarts.best_first(problem, 60_000, max_nodes=5_000)
    assert result.plan is not None, result.explain()
    assert result.first and validate(problem, result.plan) == []
    assert result.expansions <= 5_000
    # The runs are seeded: the same plan every time.
    again = restarts.best_first(problem, 60_000, max_nodes=5_000)
    assert [a.args for a in again.plan.actions] == [a.args for a in result.plan.actions]


def test_a_plan_of_the_first_run_is_the_file_orders(write, short_runs):
    problem = load_hddl(write("d.hddl", WALKS), write("p.hddl", _walks(range(0, 20))))
    ours = restarts.best_first(problem, 60_000, max_nodes=5_000)
    plain = best_first(problem, 60_000, max_nodes=5_000)
    assert [a.args for a in ours.plan.actions] == [a.args for a in plain.plan.actions]
    assert ours.expansions == plain.expansions


def test_a_run_that_proves_there_is_no_plan_ends_the_restarts(write, short_runs):
    problem = load_hddl(write("d.hddl", WALKS), write("p.hddl", _walks(range(0))))
    result = restarts.best_first(problem, 60_000, max_nodes=200_000)
    assert result.plan is None and result.complete
    assert result.expansions == best_first(problem, 60_000, max_nodes=200_000).expansions


def test_the_portfolio_restarts_its_best_first_search(write, short_runs):
    problem = load_hddl(write("d.hddl", WALKS), write("p.hddl", _walks(range(13, 18))))
    result = plan(problem, 60_000, first=True, max_nodes=5_000)
    assert result.plan is not None, result.explain()
    assert validate(problem, result.plan) == []

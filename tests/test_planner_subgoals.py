"""The facts a task stack needs and their relaxed cost from the state
(planner/heuristics/subgoals.py): the estimate that tells a reachable target from one the
search would walk to in vain."""

from __future__ import annotations

import pytest

from planner import load_hddl, plan, validate
from planner.heuristics import grounding, subgoals
from planner.heuristics.subgoals import UNREACHED, Subgoals, task_needs
from planner.search import depthfirst, portfolio, restarts
from planner.search.progression import best_first

# Items go to free levels, each at the level it names (``place-at`` binds ``?n`` to every
# level, as Freecell's methods bind a number to every successor pair).  The level only
# goes down, one step at a time, and ``shuffle`` sets any bit on the way: a level above
# the current one, or one that is not free, is a walk through every set of bits before
# it fails, and to the least work it looks as cheap as the free level below.  ``noted``
# is bookkeeping (``noted`` is in no action's precondition): it needs nothing that counts.
LEVELS = """\
(define (domain levels) (:requirements :typing :hierarchy :negative-preconditions)
  (:types num item bit)
  (:predicates (level ?n - num) (below ?a ?b - num) (placed ?x - item) (set ?b - bit)
               (isnum ?n - num) (free ?n - num) (noted ?n - num))
  (:task place :parameters (?x - item))
  (:task lower :parameters (?n - num))
  (:method place-at :parameters (?x - item ?n - num) :task (place ?x)
    :precondition (isnum ?n) :ordered-subtasks (and (lower ?n) (put ?x ?n)))
  (:method noted :parameters (?n - num) :task (lower ?n)
    :precondition (noted ?n) :ordered-subtasks (and (note ?n)))
  (:method lowered :parameters (?n - num) :task (lower ?n)
    :precondition (level ?n) :ordered-subtasks ())
  (:method step :parameters (?n ?a ?b - num) :task (lower ?n)
    :precondition (and (level ?a) (below ?b ?a))
    :ordered-subtasks (and (down ?a ?b) (lower ?n)))
  (:method shuffle :parameters (?n - num ?b - bit) :task (lower ?n)
    :precondition (not (set ?b)) :ordered-subtasks (and (flip ?b) (lower ?n)))
  (:action note :parameters (?n - num) :effect (noted ?n))
  (:action flip :parameters (?b - bit) :precondition (not (set ?b)) :effect (set ?b))
  (:action down :parameters (?a ?b - num) :precondition (and (level ?a) (below ?b ?a))
    :effect (and (not (level ?a)) (level ?b)))
  (:action put :parameters (?x - item ?n - num) :precondition (and (level ?n) (free ?n))
    :effect (and (placed ?x) (not (free ?n)))))
"""


def _levels(levels: int = 12, items: int = 3) -> str:
    """Levels n00.. (the top one current), the lowest ``items`` free, and no ``:goal``."""
    nums = " ".join(f"n{i:02d}" for i in range(levels))
    names = " ".join(f"x{i}" for i in range(items))
    facts = [f"(level n{levels - 1:02d})"]
    facts += [f"(free n{i:02d})" for i in range(items)]
    facts += [f"(isnum n{i:02d})" for i in range(levels)]
    facts += [f"(below n{i:02d} n{i + 1:02d})" for i in range(levels - 1)]
    tasks = " ".join(f"(place x{i})" for i in range(items))
    return (f"(define (problem p) (:domain levels)\n"
            f"  (:objects {nums} - num {names} - item b1 b2 b3 b4 b5 b6 b7 - bit)\n"
            f"  (:htn :ordered-subtasks (and {tasks}))\n  (:init {' '.join(facts)}))\n")


@pytest.fixture
def levels(write):
    return load_hddl(write("d.hddl", LEVELS), write("p.hddl", _levels()))


def test_what_a_task_needs_is_what_every_way_of_doing_it_needs(levels):
    needs = task_needs(levels.lifted[0])
    assert needs["put"] == (("free", (1,)), ("level", (1,)))
    # The base case's fact: the walks end in it; ``noted`` needs nothing that counts
    # and is left out of the intersection.
    assert needs["lower"] == (("level", (0,)),)
    # What ``place-at`` needs is about its own ``?n``, not the task's: nothing.
    assert needs["place"] == ()
    assert needs["flip"] == () and needs["note"] == ()


def test_a_fact_costs_the_actions_a_relaxed_plan_needs_from_the_state(levels):
    estimate = Subgoals.build(levels)
    assert estimate is not None
    initial = {key: True for key, value in levels.initial.items() if value}

    class State:
        def get(self, pred, args):
            return initial.get((pred, args))

    costs = estimate.costs(State())
    cost = {fact: costs.additive[index] for fact, index in estimate.ids.items()}
    assert cost[("level", ("n11",))] == 0
    assert cost[("level", ("n05",))] == 6          # six steps down
    assert costs.plan(estimate.ids[("level", ("n05",))]) == 6
    assert cost[("free", ("n02",))] == 0
    assert ("level", ("n12",)) not in cost         # no such level: out of reach
    assert max(costs.additive) <= UNREACHED


# ``d`` needs ``b`` and ``c``, which both need ``a``: additive costs count ``make-a`` twice.
SHARED = """\
(define (domain shared) (:requirements :hierarchy)
  (:predicates (a) (b) (c) (d))
  (:task finish :parameters ())
  (:method by-d :parameters () :task (finish) :ordered-subtasks (and (use-d)))
  (:action make-a :effect (a))
  (:action make-b :precondition (a) :effect (b))
  (:action make-c :precondition (a) :effect (c))
  (:action make-d :precondition (and (b) (c)) :effect (d))
  (:action use-d :precondition (d)))
"""


def test_a_relaxed_plan_counts_what_preconditions_share_once(write):
    problem = load_hddl(write("d.hddl", SHARED), write("p.hddl", (
        "(define (problem p) (:domain shared) (:htn :ordered-subtasks (and (finish)))"
        " (:init))")))
    estimate = Subgoals.build(problem)
    assert estimate is not None

    class Empty:
        def get(self, pred, args):
            return None

    costs = estimate.costs(Empty())
    d = estimate.ids[("d", ())]
    assert costs.additive[d] == 5  # make-d, make-b and make-c, make-a twice
    assert costs.plan(d) == 4      # make-a, make-b, make-c, make-d
    assert costs.plan(estimate.ids[("b", ())]) == 2


def test_the_estimate_takes_the_search_to_the_free_level(levels):
    alone = best_first(levels, 60_000, max_nodes=5_000)
    assert alone.plan is None  # the least work walks to every level above first
    estimate = Subgoals.build(levels)
    guided = best_first(levels, 60_000, max_nodes=5_000, subgoals=estimate)
    assert guided.plan is not None, guided.explain()
    assert validate(levels, guided.plan) == []
    assert guided.expansions < 500
    assert [a.args for a in guided.plan.actions if a.name == "put"] == [
        ("x0", "n02"), ("x1", "n01"), ("x2", "n00")]


def test_the_restarts_take_the_estimate(levels, monkeypatch):
    result = restarts.best_first(levels, 60_000, max_nodes=5_000,
                                 subgoals=Subgoals.build(levels))
    assert result.plan is not None and validate(levels, result.plan) == []
    assert result.expansions < 500
    budgets = []
    monkeypatch.setattr(restarts.progression, "best_first",
                        lambda problem, budget, **kwargs: budgets.append(budget) or result)
    restarts.best_first(levels, 60_000, subgoals=Subgoals.build(levels))
    restarts.best_first(levels, 60_000)
    assert budgets == [40_000, 30_000]  # the estimate's first run has the longer share


def test_the_portfolio_builds_it_for_a_problem_without_goals(levels, monkeypatch):
    built = []
    original = Subgoals.build

    def build(problem, actions=None):
        built.append(problem)
        return original(problem, actions)

    monkeypatch.setattr(portfolio.Subgoals, "build", staticmethod(build))
    monkeypatch.setattr(grounding, "LIMIT", 10)  # as if its methods were too many
    assert depthfirst.first_plan(levels, 60_000, max_nodes=3_000).plan is None
    result = plan(levels, 60_000, first=True, max_nodes=3_000)
    assert result.plan is not None, result.explain()
    assert validate(levels, result.plan) == []
    assert built == [levels]


def test_actions_beyond_the_limit_give_no_estimate(levels, monkeypatch):
    monkeypatch.setattr(subgoals, "ACTION_LIMIT", 10)
    assert Subgoals.build(levels) is None


def test_a_problem_without_goals_hands_over_at_the_first_branch_cut(levels, monkeypatch):
    monkeypatch.setattr(depthfirst, "MAX_DEPTH", 2)
    kept = depthfirst.first_plan(levels, 60_000)
    assert kept.plan is not None  # it went deeper, pass after pass
    handed = depthfirst.first_plan(levels, 60_000, hand_over=True)
    assert handed.plan is None and not handed.complete
    assert "a branch deeper than 2 decompositions was cut" in handed.explain()
    assert handed.expansions < kept.expansions
    assert best_first(levels, 60_000).plan is not None  # not deepened: deep at once
    monkeypatch.setattr(depthfirst, "DEEPEST", 2)
    cut = best_first(levels, 60_000)  # it cuts its branches too: it has proved nothing
    assert cut.plan is None and not cut.complete
    monkeypatch.undo()
    asked = []
    original = depthfirst.first_plan

    def first_plan(problem, *args, **kwargs):
        asked.append(kwargs.get("hand_over"))
        return original(problem, *args, **kwargs)

    monkeypatch.setattr(portfolio.depthfirst, "first_plan", first_plan)
    result = plan(levels, 60_000, first=True)
    assert result.plan is not None and validate(levels, result.plan) == []
    assert asked == [True]

"""Chains of facts a goal needs in order (planner/heuristics/landmarks.py), as the depth-first
search uses them: a stack that cannot add them in turn is refused, and the decompositions that
may add the next one are tried first.

Monroe's plan recognition in small: ``seen2`` (the goal) is added by ``observe2`` only,
which needs ``seen1``, added by ``observe1`` only, which needs ``ready``."""

from __future__ import annotations

from chores import CHORES, chores_problem, plans_with_checks

from planner.heuristics.landmarks import chains_of
from planner.search import depthfirst
from planner.search.depthfirst import first_plan

WATCH = """\
(define (domain watch) (:requirements :typing :hierarchy :negative-preconditions)
  (:types bit)
  (:predicates (on ?b - bit) (next ?a ?b - bit) (first ?b - bit) (ready) (seen1) (seen2))
  (:task top :parameters ())
  (:task look :parameters ())
  (:task chores :parameters (?b - bit))
  (:method busy :parameters (?b - bit) :task (top) :precondition (first ?b)
    :ordered-subtasks (and (chores ?b) (observe2)))
  (:method watched :parameters () :task (top)
    :ordered-subtasks (and (prepare) (look) (observe2)))
  (:method idle :parameters (?b - bit) :task (look) :precondition (first ?b)
    :ordered-subtasks (chores ?b))
  (:method looked :parameters () :task (look) :ordered-subtasks (observe1))
""" + CHORES + """\
  (:action prepare :parameters () :precondition () :effect (ready))
  (:action observe1 :parameters () :precondition (ready) :effect (seen1))
  (:action observe2 :parameters () :precondition (seen1) :effect (seen2)))
"""


def _watch(write):
    return chores_problem(write, WATCH, "(seen2)")


def test_a_chain_is_the_facts_every_achiever_of_the_next_needs(write):
    domain = _watch(write).domain
    assert chains_of(domain, [("seen2", ())]) == [
        (("ready", ()), ("seen1", ()), ("seen2", ()))]
    assert chains_of(domain, [("ready", ())]) == []  # 'prepare' needs nothing


def test_a_stack_that_cannot_add_the_chain_in_turn_is_refused(write, monkeypatch):
    """``busy`` (tried first) may add the goal, ``seen2``, but nothing before it: the goal
    check alone let it do 2^18 ways of the chores before ``observe2`` failed."""
    plans_with_checks(_watch(write), monkeypatch, ["prepare()", "observe1()", "observe2()"])


def test_the_decompositions_that_may_add_the_next_fact_are_tried_first(write, monkeypatch):
    """Without the checks (a plain pass that never ends), the order alone: ``watched``
    before ``busy`` and, once ``ready`` holds, ``looked`` before ``idle``."""
    monkeypatch.setattr(depthfirst, "PLAIN_NODES", 10_000_000)
    problem = _watch(write)
    result = first_plan(problem, 60_000, max_nodes=20_000)
    assert result.plan is not None, result.explain()
    assert [str(a) for a in result.plan.actions] == ["prepare()", "observe1()", "observe2()"]
    assert result.expansions < 50

"""Chores for the planner's tests of plan recognition in small: ``chores ?b`` sets or
skips each bit of a chain, 2^n ways of doing nothing that matters, so that a search
that does not refuse a hopeless decomposition where it is chosen runs out of nodes
(Monroe's top-level methods that cannot do the observations)."""

from __future__ import annotations

from planner import load_hddl, validate
from planner.search import depthfirst
from planner.search.depthfirst import first_plan

CHORES = """\
  (:method work :parameters (?b ?n - bit) :task (chores ?b) :precondition (next ?b ?n)
    :ordered-subtasks (and (set ?b) (chores ?n)))
  (:method rest :parameters (?b ?n - bit) :task (chores ?b) :precondition (next ?b ?n)
    :ordered-subtasks (chores ?n))
  (:method stop :parameters (?b - bit) :task (chores ?b) :ordered-subtasks ())
  (:action set :parameters (?b - bit) :precondition (not (on ?b)) :effect (on ?b))
"""
"""The methods of ``chores ?b`` and its action (the domain declares ``chores``, ``on``,
``next`` and ``first``)."""


def chores_problem(write, domain: str, goal: str, bits: int = 18, objects: str = "",
                   init: str = ""):
    """The problem of the domain ``domain`` (named ``watch``) with one task, ``top``, a
    chain of ``bits`` bits from ``b0`` (``first``), and the goal ``goal``."""
    names = " ".join(f"b{i}" for i in range(bits))
    chain = " ".join(f"(next b{i} b{i + 1})" for i in range(bits - 1))
    return load_hddl(write("d.hddl", domain), write("p.hddl", (
        f"(define (problem p) (:domain watch) (:objects {names} - bit {objects})\n"
        f"  (:htn :ordered-subtasks (and (top)))\n  (:init {chain} (first b0) {init})\n"
        f"  (:goal {goal}))\n")))


def plans_with_checks(problem, monkeypatch, actions: list[str]) -> None:
    """The depth-first search, checking decompositions after 1,000 plain nodes, plans
    ``actions`` within 20,000 nodes (the chores alone are 2^18 ways), and the plan is
    valid: the hopeless decomposition was refused where it was chosen."""
    monkeypatch.setattr(depthfirst, "PLAIN_NODES", 1_000)
    result = first_plan(problem, 60_000, max_nodes=20_000)
    assert result.plan is not None, result.explain()
    assert [str(a) for a in result.plan.actions] == actions
    assert validate(problem, result.plan) == []

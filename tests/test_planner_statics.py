"""What a task may add, judged by the problem's types and static facts (planner/statics.py).

Monroe's plan recognition in small: the goal ``seen`` is added only when ``ann``
acts (``observed``); ``busy`` (tried first) does 2^18 chores and then has a
helper act, a method variable that the lifted analysis cannot tell from
``ann``.  The helpers are of type ``helper`` and must be ``trusted`` (a fact no
action changes), so neither ``busy`` way may reach the goal."""

from __future__ import annotations

from planner import depthfirst, load_hddl, validate
from planner.depthfirst import first_plan

WATCH = """\
(define (domain watch) (:requirements :typing :hierarchy :negative-preconditions :equality)
  (:types bit agent - object helper - agent)
  (:constants ann - agent)
  (:predicates (on ?b - bit) (next ?a ?b - bit) (first ?b - bit) (trusted ?a - agent)
               (ready) (seen))
  (:task top :parameters ())
  (:task chores :parameters (?b - bit))
  (:task act :parameters (?who - agent))
  (:task help :parameters ())
  (:method busy :parameters (?b - bit) :task (top) :precondition (first ?b)
    :ordered-subtasks (and (chores ?b) (help)))
  (:method watched :parameters (?who - agent) :task (top)
    :ordered-subtasks (and (prepare) (act ?who)))
  (:method helped :parameters (?who - helper) :task (help) :ordered-subtasks (act ?who))
  (:method asked :parameters (?who - agent) :task (help)
    :ordered-subtasks (and (check ?who) (act ?who)))
  (:method observed :parameters (?who - agent) :task (act ?who)
    :precondition (= ?who ann) :ordered-subtasks (observe))
  (:method plain :parameters (?who - agent) :task (act ?who) :ordered-subtasks ())
  (:method work :parameters (?b ?n - bit) :task (chores ?b) :precondition (next ?b ?n)
    :ordered-subtasks (and (set ?b) (chores ?n)))
  (:method rest :parameters (?b ?n - bit) :task (chores ?b) :precondition (next ?b ?n)
    :ordered-subtasks (chores ?n))
  (:method stop :parameters (?b - bit) :task (chores ?b) :ordered-subtasks ())
  (:action check :parameters (?who - agent) :precondition (trusted ?who) :effect ())
  (:action set :parameters (?b - bit) :precondition (not (on ?b)) :effect (on ?b))
  (:action prepare :parameters () :precondition () :effect (ready))
  (:action observe :parameters () :precondition (ready) :effect (seen)))
"""


def _watch(write, trusted: str = "bob", bits: int = 18):
    objects = " ".join(f"b{i}" for i in range(bits))
    chain = " ".join(f"(next b{i} b{i + 1})" for i in range(bits - 1))
    return load_hddl(write("d.hddl", WATCH), write("p.hddl", (
        f"(define (problem p) (:domain watch) (:objects {objects} - bit bob - helper)\n"
        f"  (:htn :ordered-subtasks (and (top)))\n"
        f"  (:init {chain} (first b0) (trusted {trusted}))\n  (:goal (seen)))\n")))


def test_a_method_variable_whose_type_or_static_facts_exclude_a_value_does_not_add_for_it(
        write):
    domain = _watch(write).domain
    assert domain.may_add("act", ("ann",), "seen", ())
    # 'helped' needs a helper (ann is not one), 'asked' a trusted agent (only bob is).
    assert not domain.may_add("help", (), "seen", ())
    assert domain.may_add("top", (), "seen", ())  # through 'watched'
    trusting = _watch(write, trusted="ann").domain
    assert trusting.may_add("help", (), "seen", ())  # 'asked' may have ann act


def test_a_decomposition_whose_helpers_cannot_reach_the_goal_is_refused(write, monkeypatch):
    """Before the static filter, ``help`` "may add" ``seen`` and ``busy`` was searched
    through 2^18 ways of doing the chores."""
    monkeypatch.setattr(depthfirst, "PLAIN_NODES", 1_000)  # the checks start after
    problem = _watch(write)
    result = first_plan(problem, 60_000, max_nodes=20_000)
    assert result.plan is not None, result.explain()
    assert [str(a) for a in result.plan.actions] == ["prepare()", "observe()"]
    assert validate(problem, result.plan) == []

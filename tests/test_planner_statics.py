"""What a task may add, judged by the problem's types and static facts (planner/model/statics.py).

Monroe's plan recognition in small: the goal ``seen`` is added only when ``ann``
acts (``observed``); ``busy`` (tried first) does 2^18 chores and then has a
helper act, a method variable that the lifted analysis cannot tell from
``ann``.  The helpers are of type ``helper`` and must be ``trusted`` (a fact no
action changes), so neither ``busy`` way may reach the goal."""

from __future__ import annotations

from chores import CHORES, chores_problem, plans_with_checks

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
  (:action check :parameters (?who - agent) :precondition (trusted ?who) :effect ())
""" + CHORES + """\
  (:action prepare :parameters () :precondition () :effect (ready))
  (:action observe :parameters () :precondition (ready) :effect (seen)))
"""


def _watch(write, trusted: str = "bob"):
    return chores_problem(write, WATCH, "(seen)", objects="bob - helper",
                          init=f"(trusted {trusted})")


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
    plans_with_checks(_watch(write), monkeypatch, ["prepare()", "observe()"])

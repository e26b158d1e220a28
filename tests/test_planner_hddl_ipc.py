"""The IPC mode's mechanisms on small HDDL problems: names as the files spell them,
entry conditions checked by the binders, and a depth cut that grows."""

from __future__ import annotations

import pytest

from planner import load_hddl, plan, validate
from planner.io.ipc import write_ipc
from planner.model.state import FactState
from planner.search import depthfirst

MIXED = """\
(define (domain Shop)
  (:requirements :typing :hierarchy)
  (:types Crate)
  (:predicates (At ?c - Crate) (Done ?c - Crate))
  (:task Deliver :parameters (?c - Crate))
  (:method M-Deliver
    :parameters (?c - Crate)
    :task (Deliver ?c)
    :ordered-subtasks (and (Load ?c)))
  (:action Load :parameters (?c - Crate) :precondition (At ?c) :effect (Done ?c)))
"""

MIXED_PROBLEM = """\
(define (problem P1) (:domain Shop)
  (:objects BigCrate - Crate)
  (:htn :ordered-subtasks (and (Deliver BigCrate)))
  (:init (At BigCrate)))
"""


def _load(write, domain: str, problem: str):
    return load_hddl(write("domain.hddl", domain), write("problem.hddl", problem))


def test_ipc_plans_spell_names_as_the_files_do(write):
    problem = _load(write, MIXED, MIXED_PROBLEM)
    result = plan(problem, 5_000, first=True)
    assert result.plan is not None
    assert write_ipc(result.plan, problem.spelling).splitlines() == [
        "==>", "0 Load BigCrate", "root 1", "1 Deliver BigCrate -> M-Deliver 0", "<=="]
    # Without the spelling, the names as read (HDDL is case-insensitive).
    assert "0 load bigcrate" in write_ipc(result.plan)


def _cards(mark_effect: str) -> str:
    """``pick ?c`` is free in ``m-pick``; ``handle ?c``'s one method marks the card (a
    bookkeeping action) and then takes it, which needs the card clear."""
    return f"""\
(define (domain cards)
  (:requirements :typing :hierarchy)
  (:types card)
  (:predicates (clear ?c - card) (flag ?c - card) (taken ?c - card))
  (:task pick :parameters ())
  (:task handle :parameters (?c - card))
  (:method m-pick
    :parameters (?c - card)
    :task (pick)
    :ordered-subtasks (and (handle ?c)))
  (:method m-handle
    :parameters (?c - card)
    :task (handle ?c)
    :ordered-subtasks (and (mark ?c) (take ?c)))
  (:action mark :parameters (?c - card) :effect {mark_effect})
  (:action take :parameters (?c - card) :precondition (clear ?c) :effect (taken ?c)))
"""


CARDS_PROBLEM = """\
(define (problem p) (:domain cards)
  (:objects a b c d e - card)
  (:htn :ordered-subtasks (and (pick)))
  (:init (clear e)))
"""


def _bindings(problem, method: str, **task_args: str) -> list[dict]:
    """The bindings a method's binder proposes in the initial state, for the task's
    arguments ``task_args`` (by parameter name, without '?')."""
    decomposition = next(d for m in problem.domain.methods.values()
                         for d in m.decompositions if d.name == method)
    state = FactState(dict(problem.initial), problem.domain.patterns)
    return list(decomposition.bind(task_args, state))


def test_a_binder_checks_what_a_later_subtask_needs_when_nothing_before_changes_it(write):
    problem = _load(write, _cards("(flag ?c)"), CARDS_PROBLEM)
    # 'take' needs (clear ?c); 'mark' before it cannot change 'clear', and 'handle' has one
    # method: so (clear ?c) must hold where 'pick' is decomposed, and only e is proposed.
    assert _bindings(problem, "m-pick") == [{"?c": "e"}]
    assert _bindings(problem, "m-pick") == [{"c": "e"}] or _bindings(problem, "m-pick") == [
        {"?c": "e"}]
    result = plan(problem, 5_000, first=True)
    assert [str(a) for a in result.plan.actions] == ["mark(e)", "take(e)"]
    assert validate(problem, result.plan) == []


def test_a_condition_an_earlier_subtask_may_change_is_not_required_at_entry(write):
    problem = _load(write, _cards("(clear ?c)"), CARDS_PROBLEM)
    # Here 'mark' makes the card clear: every card may be picked, the first one first.
    assert len(_bindings(problem, "m-pick")) == 5
    result = plan(problem, 5_000, first=True)
    assert [str(a) for a in result.plan.actions] == ["mark(a)", "take(a)"]
    assert validate(problem, result.plan) == []


COUNT = """\
(define (domain count)
  (:requirements :typing :hierarchy)
  (:types num)
  (:predicates (next ?n ?m - num) (last ?n - num) (ticked ?n - num))
  (:task count :parameters (?n - num))
  (:method step
    :parameters (?n ?m - num)
    :task (count ?n)
    :precondition (next ?n ?m)
    :ordered-subtasks (and (tick ?n) (count ?m)))
  (:method stop
    :parameters (?n - num)
    :task (count ?n)
    :precondition (last ?n)
    :ordered-subtasks (and))
  (:action tick :parameters (?n - num) :effect (ticked ?n)))
"""

COUNT_PROBLEM = """\
(define (problem twelve) (:domain count)
  (:objects n0 n1 n2 n3 n4 n5 n6 n7 n8 n9 n10 n11 - num)
  (:htn :ordered-subtasks (and (count n0)))
  (:init (next n0 n1) (next n1 n2) (next n2 n3) (next n3 n4) (next n4 n5) (next n5 n6)
         (next n6 n7) (next n7 n8) (next n8 n9) (next n9 n10) (next n10 n11) (last n11)))
"""


def test_a_pass_that_cut_deep_branches_is_followed_by_a_deeper_one(write, monkeypatch):
    monkeypatch.setattr(depthfirst, "MAX_DEPTH", 4)
    problem = _load(write, COUNT, COUNT_PROBLEM)
    result = plan(problem, 5_000, first=True)
    assert result.plan is not None, result.explain()
    assert len(result.plan.actions) == 11
    assert validate(problem, result.plan) == []


def test_the_depth_stops_growing_at_the_deepest_allowed(write, monkeypatch):
    monkeypatch.setattr(depthfirst, "MAX_DEPTH", 2)
    monkeypatch.setattr(depthfirst, "DEEPEST", 8)
    problem = _load(write, COUNT, COUNT_PROBLEM)
    result = plan(problem, 5_000, first=True)
    assert result.plan is None
    assert "branches deeper than 8 decompositions were cut" in result.explain()


@pytest.mark.parametrize("depth", [12, 100])
def test_a_deep_enough_first_pass_needs_no_other(write, monkeypatch, depth):
    monkeypatch.setattr(depthfirst, "MAX_DEPTH", depth)
    problem = _load(write, COUNT, COUNT_PROBLEM)
    assert len(plan(problem, 5_000, first=True).plan.actions) == 11


def _haul(mover: str) -> str:
    """``at`` says where vehicles and packages are; ``move`` moves a ``mover``."""
    return f"""\
(define (domain haul)
  (:requirements :typing :hierarchy)
  (:types vehicle package - thing place)
  (:predicates (at ?x - thing ?l - place) (in ?p - package ?v - vehicle))
  (:task deliver :parameters (?p - package))
  (:method m-deliver
    :parameters (?p - package ?v - vehicle ?l - place)
    :task (deliver ?p)
    :ordered-subtasks (and (move ?v ?l) (pick ?v ?p ?l)))
  (:action move :parameters (?v - {mover} ?l - place) :effect (at ?v ?l))
  (:action pick :parameters (?v - vehicle ?p - package ?l - place)
    :precondition (at ?p ?l) :effect (and (not (at ?p ?l)) (in ?p ?v))))
"""


HAUL_PROBLEM = """\
(define (problem p) (:domain haul)
  (:objects truck - vehicle box - package depot port yard - place)
  (:htn :ordered-subtasks (and (deliver box)))
  (:init (at truck depot) (at box yard)))
"""


def test_a_condition_on_facts_of_another_type_than_those_changed_is_required(write):
    problem = _load(write, _haul("vehicle"), HAUL_PROBLEM)
    # 'move' changes where vehicles are, never where a package is: (at box ?l) holds at
    # the method's entry, so ?l is the yard at once.
    assert _bindings(problem, "m-deliver", p="box") == [{"?p": "box", "?v": "truck", "?l": "yard"}]
    result = plan(problem, 5_000, first=True)
    assert [str(a) for a in result.plan.actions] == ["move(truck, yard)",
                                                     "pick(truck, box, yard)"]


def test_a_condition_on_facts_of_an_overlapping_type_is_not_required(write):
    problem = _load(write, _haul("thing"), HAUL_PROBLEM)
    # Here 'move' may move any thing, a package too: every place is proposed.
    assert len(_bindings(problem, "m-deliver", p="box")) == 3

"""The goal facts' relaxed support through the task stack's actions
(planner/heuristics/support.py), in the goal-guided search (planner/search/progression.py)."""

from __future__ import annotations

from planner import load_hddl, validate
from planner.heuristics.support import Support
from planner.model.state import FactState
from planner.search.progression import BestFirst

# Finishing in Woodworking's shape: a part is glazed (one action) or sanded and varnished
# (two), and ``m-help`` sands its part and varnishes *any* part (Woodworking's
# ``method16``, whose ``do_colour`` takes a part of its own).  Varnishing needs the part
# untreated, and nothing makes a treated part untreated again.
FINISHING = """\
(define (domain finishing) (:requirements :typing :hierarchy :negative-preconditions)
  (:types part colour)
  (:predicates (untreated ?p - part) (smooth ?p - part) (glazed ?p - part)
               (varnished ?p - part) (colour ?p - part ?c - colour))
  (:task finish :parameters (?p - part ?c - colour))
  (:task touch :parameters (?p - part ?c - colour))
  (:method m-glaze :parameters (?p - part ?c - colour) :task (finish ?p ?c)
    :ordered-subtasks (and (glaze ?p ?c)))
  (:method m-varnish :parameters (?p - part ?c - colour) :task (finish ?p ?c)
    :ordered-subtasks (and (sand ?p) (varnish ?p ?c)))
  (:method m-help :parameters (?p ?q - part ?c - colour) :task (finish ?p ?c)
    :ordered-subtasks (and (sand ?p) (touch ?q ?c)))
  (:method t-varnish :parameters (?q - part ?c - colour) :task (touch ?q ?c)
    :ordered-subtasks (and (varnish ?q ?c)))
  (:action glaze :parameters (?p - part ?c - colour) :precondition (untreated ?p)
    :effect (and (not (untreated ?p)) (glazed ?p) (colour ?p ?c)))
  (:action sand :parameters (?p - part) :precondition (untreated ?p) :effect (smooth ?p))
  (:action varnish :parameters (?p - part ?c - colour)
    :precondition (and (untreated ?p) (smooth ?p))
    :effect (and (not (untreated ?p)) (varnished ?p) (colour ?p ?c))))
"""


def _finishing(parts: int) -> str:
    names = " ".join(f"p{i}" for i in range(parts))
    params = " ".join(f"?c{i}" for i in range(parts))
    tasks = " ".join(f"(finish p{i} ?c{i})" for i in range(parts))
    init = " ".join(f"(untreated p{i})" for i in range(parts))
    goal = " ".join(f"(varnished p{i}) (colour p{i} c{i % 3})" for i in range(parts))
    return (f"(define (problem p) (:domain finishing)\n"
            f"  (:objects {names} - part c0 c1 c2 - colour)\n"
            f"  (:htn :parameters ({params} - colour) :ordered-subtasks (and {tasks}))\n"
            f"  (:init {init})\n  (:goal (and {goal})))\n")


def _stack(tasks: list[tuple[str, tuple]]) -> tuple | None:
    agenda = None
    for name, args in reversed(tasks):
        agenda = (name, args, None, hash((name, args, agenda[3] if agenda else 0)), agenda)
    return agenda


def test_a_goal_fact_whose_adders_need_a_fact_no_task_gives_back_has_no_support(write):
    problem = load_hddl(write("d.hddl", FINISHING), write("p.hddl", _finishing(3)))
    goals = [key for key, value in problem.goals.items() if value is True]
    support = Support.of(*problem.lifted, goals)
    assert support is not None
    varnished = goals.index(("varnished", ("p0",)))
    # p0 glazed: untreated no more. finish(p1) may varnish any part (m-help), so the lifted
    # "may add" keeps (varnished p0) within reach; varnishing p0 needs (untreated p0),
    # which no action below the stack adds.
    glazed = {**dict(problem.initial), ("untreated", ("p0",)): None,
              ("glazed", ("p0",)): True, ("colour", ("p0", "c0")): True}
    state = FactState(glazed, problem.domain.patterns)
    stack = _stack([("finish", ("p1", "c1")), ("finish", ("p2", "c2"))])
    assert problem.domain.may_add("finish", ("p1", "c1"), "varnished", ("p0",))
    assert support.unsupported(frozenset([varnished]), state, stack) == varnished
    # p0 sanded and still untreated: m-help's touch may varnish it; not sanded, it may
    # not (only a part's own finish sands it).
    sanded = FactState({**dict(problem.initial), ("smooth", ("p0",)): True},
                       problem.domain.patterns)
    assert support.unsupported(frozenset([varnished]), sanded, stack) is None
    fresh = FactState(dict(problem.initial), problem.domain.patterns)
    assert support.unsupported(frozenset([varnished]), fresh, stack) == varnished
    # Nor is a goal fact of p1 out of support while finish(p1) is left.
    assert support.unsupported(frozenset([goals.index(("varnished", ("p1",)))]),
                               state, stack) is None


def test_the_search_leaves_a_part_glazed_at_once_and_plans(write):
    # Glazing is the least work and meets the colour, so the greedy search glazes every
    # part, and learns at the last task that none is varnished; without the support of the
    # goal facts it then backtracks over every part's choice (no plan in 3,000 nodes).
    problem = load_hddl(write("d.hddl", FINISHING), write("p.hddl", _finishing(10)))
    result = BestFirst(problem).run(60_000, 3_000)
    assert result.plan is not None, result.explain()
    assert validate(problem, result.plan) == []
    assert not any(a.name == "glaze" for a in result.plan.actions)
    assert sorted(a.args[0] for a in result.plan.actions if a.name == "varnish") == [
        f"p{i}" for i in range(10)]


def test_the_check_gives_itself_up_when_it_drops_no_node(write):
    # Where the lifted "may add" already tells the dead ends, the check drops nothing and
    # only costs: after TRIAL nodes without a drop it is not asked again.
    from planner.heuristics.support import TRIAL

    problem = load_hddl(write("d.hddl", FINISHING), write("p.hddl", _finishing(3)))
    goals = [key for key, value in problem.goals.items() if value is True]
    state = FactState(dict(problem.initial), problem.domain.patterns)
    stack = _stack([("finish", ("p0", "c0")), ("finish", ("p1", "c1"))])
    false = frozenset([goals.index(("varnished", ("p0",)))])
    idle, busy = Support.of(*problem.lifted, goals), Support.of(*problem.lifted, goals)
    assert idle is not None and busy is not None
    assert busy.unsupported(false, state, stack[4]) is not None  # finish(p0) gone: a drop
    for _ in range(TRIAL):
        assert idle.useful and idle.unsupported(false, state, stack) is None
        busy.unsupported(false, state, stack)
    assert not idle.useful and busy.useful

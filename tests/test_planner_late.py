"""Late binding of method variables (planner/search/late.py) and the goal facts a task stack
may still add (planner/heuristics/reach.py), in the goal-guided search
(planner/search/progression.py)."""

from __future__ import annotations

from planner import load_hddl, validate
from planner.io.ipc import read_ipc, write_ipc
from planner.model.state import FactState
from planner.search.depthfirst import DepthFirst
from planner.search.late import Unbound, search_patterns
from planner.search.progression import BestFirst, best_first

# A workshop in Woodworking's shape: ``finish`` names a machine its method never looks at
# (it only passes it on), and ``paint`` sprays with a machine of its own choosing.
WORKSHOP = """\
(define (domain workshop) (:requirements :typing :hierarchy :negative-preconditions)
  (:types part colour machine - object sprayer - machine)
  (:predicates (raw ?p - part) (sanded ?p - part) (colour ?p - part ?c - colour)
               (offers ?m - machine ?c - colour))
  (:task finish :parameters (?p - part ?c - colour))
  (:task paint :parameters (?p - part ?c - colour ?m - machine))
  (:method m-finish :parameters (?p - part ?c - colour ?m - machine) :task (finish ?p ?c)
    :ordered-subtasks (and (sand ?p) (paint ?p ?c ?m)))
  (:method m-paint :parameters (?p - part ?c - colour ?m - sprayer ?n - machine)
    :task (paint ?p ?c ?m) :ordered-subtasks (and (spray ?p ?n ?c)))
  (:action sand :parameters (?p - part) :precondition (raw ?p)
    :effect (and (not (raw ?p)) (sanded ?p)))
  (:action spray :parameters (?p - part ?m - machine ?c - colour)
    :precondition (and (sanded ?p) (offers ?m ?c)) :effect (colour ?p ?c)))
"""


def _workshop(parts: int, goal: dict[int, str], machines: int = 20) -> str:
    names = " ".join(f"p{i}" for i in range(parts))
    kinds = " ".join(f"m{i:02d}" for i in range(machines))
    params = " ".join(f"?c{i}" for i in range(parts))
    tasks = " ".join(f"(finish p{i} ?c{i})" for i in range(parts))
    init = " ".join(f"(raw p{i})" for i in range(parts)) + " " + " ".join(
        f"(offers m{i:02d} c{i % 5})" for i in range(machines))
    wanted = " ".join(f"(colour p{i} {c})" for i, c in goal.items())
    return (f"(define (problem p) (:domain workshop)\n"
            f"  (:objects {names} - part c0 c1 c2 c3 c4 c9 - colour {kinds} - machine\n"
            f"            s1 s2 - sprayer)\n"
            f"  (:htn :parameters ({params} - colour) :ordered-subtasks (and {tasks}))\n"
            f"  (:init {init})\n  (:goal (and {wanted})))\n")


def test_a_variable_no_condition_reads_is_left_unbound_by_the_late_binder(write):
    problem = load_hddl(write("d.hddl", WORKSHOP), write("p.hddl", _workshop(3, {0: "c3"})))
    dec = problem.domain.methods["finish"].decompositions[0]
    state = FactState(dict(problem.initial), search_patterns(problem.domain, problem.tasks))
    env = {"p": "p0", "c": "c3"}
    eager = list(dec.bind(env, state))
    assert len(eager) == 22  # every machine, sprayers included: each a successor
    (late, subst), = list(dec.late(env, state))
    assert subst == {} and isinstance(late["?m"], Unbound)
    assert late["?m"].objects == tuple(sorted([f"m{i:02d}" for i in range(20)] + ["s1", "s2"]))


def test_a_placeholder_is_bound_by_the_facts_of_the_task_that_needs_it(write):
    goal = {0: "c3", 1: "c1", 2: "c4"}
    problem = load_hddl(write("d.hddl", WORKSHOP), write("p.hddl", _workshop(3, goal)))
    result = BestFirst(problem).run(60_000, 200)
    assert result.plan is not None, result.explain()
    assert validate(problem, result.plan) == []
    sprays = [a.args for a in result.plan.actions if a.name == "spray"]
    assert [(p, c) for p, _, c in sprays] == [("p0", "c3"), ("p1", "c1"), ("p2", "c4")]
    assert all(m in {f"m{i:02d}" for i in range(20)} for _, m, _ in sprays)
    text = write_ipc(result.plan, problem.spelling)
    assert "?" not in text and "#" not in text  # every placeholder has its value
    finishes = [line for line in text.splitlines() if " finish " in line]
    assert len(finishes) == 3
    # The machine m-finish passes on was never read: it takes a value m-paint allows
    # (a sprayer: the placeholder was narrowed to m-paint's type).
    paints = [line.split() for line in text.splitlines() if " paint " in line]
    assert [words[4] for words in paints] == ["s1", "s1", "s1"]
    assert read_ipc(text)


def test_a_goal_fact_no_task_left_may_add_ends_the_branch(write):
    # p0 must be coloured c9, which no machine offers: once p0 is sprayed another colour,
    # no task left may colour it, and the search need not colour the other parts.
    goal = {0: "c9", 1: "c1"}
    problem = load_hddl(write("d.hddl", WORKSHOP), write("p.hddl", _workshop(7, goal)))
    result = BestFirst(problem).run(60_000, 3_000)
    assert result.plan is None and result.complete, result.explain()
    assert "(colour p0 c9) == True" in result.explain()


def test_the_search_binds_every_variable_at_once_first_then_late(write):
    # best_first's first search binds m-finish's machine at once (every sprayer tried,
    # the last made first); what it finds is as valid as the late-bound plan.
    goal = {0: "c3", 1: "c1"}
    problem = load_hddl(write("d.hddl", WORKSHOP), write("p.hddl", _workshop(2, goal)))
    eager = BestFirst(problem, defer=False).run(60_000, 200)
    late = BestFirst(problem).run(60_000, 200)
    result = best_first(problem, 60_000)
    assert eager.plan is not None and late.plan is not None and result.plan is not None
    assert validate(problem, result.plan) == []
    assert write_ipc(result.plan, problem.spelling) == write_ipc(eager.plan, problem.spelling)
    assert write_ipc(eager.plan) != write_ipc(late.plan)  # the machines differ


ALCHEMY = """\
(define (domain alchemy) (:requirements :typing :hierarchy :negative-preconditions)
  (:types stuff)
  (:predicates (have ?x - stuff))
  (:task get :parameters (?x - stuff))
  (:method already :parameters (?x - stuff) :task (get ?x) :precondition (have ?x)
    :ordered-subtasks ())
  (:method transmute :parameters (?x ?y - stuff) :task (get ?x)
    :precondition (not (have ?x)) :ordered-subtasks (and (get ?y) (convert ?y ?x)))
  (:action convert :parameters (?y ?x - stuff) :precondition (have ?y)
    :effect (and (not (have ?y)) (have ?x))))
"""


def test_a_placeholder_is_not_taken_for_the_task_an_ancestor_decomposed(write):
    # transmute's ?y is read by no condition: get(?y) is decomposed in the very state
    # where get(gold) was, and is not the same task (a placeholder equals anything,
    # but the repeated-decomposition check must not count it as get(gold)).
    problem = load_hddl(write("d.hddl", ALCHEMY), write("p.hddl", (
        "(define (problem p) (:domain alchemy) (:objects gold lead - stuff)\n"
        "  (:htn :ordered-subtasks (and (get gold))) (:init (have lead)))\n")))
    result = BestFirst(problem).run(60_000, 1_000)
    assert result.plan is not None, result.explain()
    assert validate(problem, result.plan) == []
    assert [(a.name, a.args) for a in result.plan.actions] == [("convert", ("lead", "gold"))]
    # The check itself: get(?y) below get(gold), in the same state, is not a repetition,
    # nor is a placeholder the same as another placeholder; it is the same as itself.
    steps = DepthFirst(problem)
    placeholder, other = Unbound("?y#1", ("gold", "lead")), Unbound("?y#2", ("gold", "lead"))
    parent = (None, ("get", ("gold",)), 0, 7, 1, 1)
    for args in [(placeholder,), (placeholder,)]:  # the second time looks at the ancestors
        assert not steps._repeats("get", args, parent, 7)
    assert not steps._repeats("get", (other,), (parent, ("get", (placeholder,)), 0, 7, 2, 2), 7)
    assert not steps._repeats("get", (other,), (parent, ("get", (placeholder,)), 0, 7, 2, 2), 7)
    assert steps._repeats("get", (placeholder,), (parent, ("get", (placeholder,)), 0, 7, 2, 2), 7)

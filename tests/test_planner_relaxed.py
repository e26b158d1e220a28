"""The ground model (planner/heuristics/grounding.py) and the relaxed-composition heuristic
(planner/heuristics/relaxed.py) that guides the best-first search where the hierarchy alone
does not: a miniature of AssemblyHierarchical, where any two ports may be connected before the
chain is checked."""

from __future__ import annotations

import math

from planner import load_hddl, plan, validate
from planner.heuristics import grounding
from planner.search.progression import BestFirst, best_first, relaxed_model

CABLING = """\
(define (domain cabling) (:requirements :typing :hierarchy :negative-preconditions)
  (:types port)
  (:predicates (fits ?a ?b - port) (linked ?a ?b - port) (through ?a ?b - port)
               (busy ?p - port) (sealed) (done))
  (:task wire :parameters (?from ?to - port))
  (:task check :parameters (?from ?to - port))
  (:task join :parameters (?a ?b - port))
  (:method plug :parameters (?from ?to ?a ?b - port) :task (wire ?from ?to)
    :ordered-subtasks (and (join ?a ?b) (wire ?from ?to)))
  (:method join-them :parameters (?a ?b - port) :task (join ?a ?b)
    :ordered-subtasks (and (connect ?a ?b)))
  (:method seal :parameters (?from ?to - port) :task (wire ?from ?to)
    :ordered-subtasks (and (close) (check ?from ?to)))
  (:method hop :parameters (?from ?to ?mid ?next - port) :task (check ?from ?to)
    :precondition (and (linked ?from ?mid) (through ?mid ?next))
    :ordered-subtasks (and (check ?next ?to)))
  (:method arrive :parameters (?from ?to - port) :task (check ?from ?to)
    :precondition (linked ?from ?to) :ordered-subtasks (and (finish)))
  (:action connect :parameters (?a ?b - port)
    :precondition (and (not (sealed)) (not (busy ?a)) (not (busy ?b)) (fits ?a ?b))
    :effect (and (linked ?a ?b) (busy ?a) (busy ?b)))
  (:action close :parameters () :effect (sealed))
  (:action finish :parameters () :precondition (sealed) :effect (done)))
"""


def _cables(count: int) -> str:
    """``src`` to ``dst`` through cables: ``src`` fits the first cable's ends, ``dst`` the
    last one's, and the ends of any two cables fit each other, so that nothing but the
    chain's check tells the right connections from the others."""
    ends = [f"c{i}{end}" for i in range(count) for end in "ab"]
    through = " ".join(f"(through c{i}a c{i}b) (through c{i}b c{i}a)" for i in range(count))
    pairs = [(a, b) for a in ends for b in ends if a[:-1] != b[:-1]]
    pairs += [("src", "c0a"), ("src", "c0b"), (f"c{count - 1}a", "dst"),
              (f"c{count - 1}b", "dst")]
    fits = " ".join(f"(fits {a} {b}) (fits {b} {a})" for a, b in pairs)
    ports = ["src", "dst", *ends]
    return (f"(define (problem p) (:domain cabling) (:objects {' '.join(ports)} - port)\n"
            f"  (:htn :ordered-subtasks (and (wire src dst)))\n"
            f"  (:init {through} {fits})\n  (:goal (done)))\n")


def test_the_ground_model_keeps_what_the_network_reaches_and_can_finish(write):
    problem = load_hddl(write("d.hddl", CABLING), write("p.hddl", _cables(2)))
    model = grounding.ground(*problem.lifted)
    assert model is not None
    assert ("wire", ("src", "dst")) in model.tasks
    # Only checks towards dst are reached from the network; the ends of one cable fit
    # nothing of each other, so their connection is not in the model.
    assert ("check", ("c0b", "dst")) in model.tasks
    assert not any(t[0] == "check" and t[1][1] != "dst" for t in model.tasks)
    assert ("connect", ("c0a", "c0b")) not in model.tasks
    assert ("connect", ("src", "c0a")) in model.tasks


def test_the_ground_model_is_given_up_when_too_large_or_the_network_has_parameters(
        write, monkeypatch):
    problem = load_hddl(write("d.hddl", CABLING), write("p.hddl", _cables(2)))
    monkeypatch.setattr(grounding, "LIMIT", 50)
    assert grounding.ground(*problem.lifted) is None
    monkeypatch.undo()
    free = _cables(2).replace("(:htn :ordered-subtasks (and (wire src dst)))",
                              "(:htn :parameters (?x - port) "
                              ":ordered-subtasks (and (wire ?x dst)))")
    problem = load_hddl(write("d.hddl", CABLING), write("f.hddl", free))
    assert grounding.ground(*problem.lifted) is None and relaxed_model(problem) is None


def test_the_relaxed_plan_counts_a_connection_the_chain_needs_as_already_planned(write):
    problem = load_hddl(write("d.hddl", CABLING), write("p.hddl", _cables(2)))
    search = BestFirst(problem, relaxed_model(problem))
    _, first = search.steps._start()
    state, state_hash, agenda, _ = first
    relaxed = search.relaxed
    assert relaxed is not None
    whole, unmet = relaxed.estimate(state, state_hash, agenda)
    assert unmet == 1
    assert whole == 3 + 2  # src to a cable, that cable to the other, on to dst; close, finish

    def with_connect(a: str, b: str) -> float:
        top = ("connect", (a, b), None, hash(("connect", a, b)), agenda)
        return relaxed.estimate(state, state_hash, top)[0]

    # The relaxed plan of the check links src to an end of the first cable: one of
    # those two connections adds nothing to it, a connection no chain needs adds one.
    assert min(with_connect("src", end) for end in ("c0a", "c0b")) == whole
    assert with_connect("c1a", "c0a") == whole + 1
    # A task that is out of reach makes the stack a dead end.
    dead = ("connect", ("c0a", "c0b"), None, hash("dead"), agenda)
    assert relaxed.estimate(state, state_hash, dead)[0] == math.inf


def test_the_relaxed_heuristic_finds_the_chain_the_least_work_leaves_to_chance(write):
    problem = load_hddl(write("d.hddl", CABLING), write("p.hddl", _cables(5)))
    blind = best_first(problem, 120_000, max_nodes=3_000)
    assert blind.plan is None
    guided = best_first(problem, 120_000, max_nodes=3_000, relaxed=relaxed_model(problem))
    assert guided.plan is not None, guided.explain()
    assert validate(problem, guided.plan) == []
    names = [a.name for a in guided.plan.actions]
    # src to the first cable, its other end to the last cable, on to dst: no connection
    # undone or wasted.
    assert names == ["connect"] * 3 + ["close", "finish"]


def test_the_portfolio_runs_the_relaxed_search_after_the_depth_first_one(write):
    problem = load_hddl(write("d.hddl", CABLING), write("p.hddl", _cables(5)))
    result = plan(problem, 120_000, first=True, max_nodes=3_000)
    assert result.plan is not None, result.explain()
    assert validate(problem, result.plan) == []
    assert len(result.plan.actions) == 5


def test_every_action_of_a_plan_found_without_it_is_in_the_ground_model(write):
    # The model over-approximates what a plan can hold: a plan of the depth-first
    # search, which knows nothing of it, names only ground actions it has.
    problem = load_hddl(write("d.hddl", CABLING), write("p.hddl", _cables(2)))
    found = plan(problem, 120_000, first=True)
    assert found.plan is not None
    model = grounding.ground(*problem.lifted)
    assert model is not None
    assert all((a.name, tuple(a.args)) in model.tasks for a in found.plan.actions)


def test_the_relaxed_search_decomposes_by_the_ground_bindings_that_hold_in_the_state(write):
    problem = load_hddl(write("d.hddl", CABLING), write("p.hddl", _cables(2)))
    search = BestFirst(problem, relaxed_model(problem))
    steps = search.steps
    assert steps.ground is not None
    _, first = steps._start()
    state, state_hash, agenda, trail = first
    methods = problem.domain.methods

    def children(task: str, args: tuple) -> list[tuple[str, dict]]:
        out = steps._decompose(methods[task], args, agenda[2], state, state_hash, None, trail)
        return [(node[3][0][5], node[3][0][6]) for node in out]

    # plug's ?a ?b are left to their type (join is a compound task): the model's
    # bindings are the pairs that fit, not every pair of ports.
    plugs = [b for name, b in children("wire", ("src", "dst")) if name == "plug"]
    assert plugs and len(plugs) == len(steps.ground[("wire", ("src", "dst"))]["plug"])
    assert all(f"(fits {b['?a']} {b['?b']})" in _cables(2) for b in plugs)
    assert len(plugs) < 6 * 5
    # A method whose variables its precondition binds keeps its binder.
    assert "hop" not in steps.ground[("check", ("src", "dst"))]
    assert children("check", ("src", "dst")) == []  # nothing is linked yet

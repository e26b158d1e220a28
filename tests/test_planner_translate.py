"""HDDL translated into the planner's model: semantics, binding, goal protection, refusals."""

from __future__ import annotations

import dataclasses

import pytest

from planner import load_hddl, plan, validate
from planner.io.ipc import read_ipc, shape, write_ipc
from userfiles.errors import FileError

DEPOT = """\
(define (domain depot)
  (:requirements :typing :hierarchy :negative-preconditions :conditional-effects
                 :universal-preconditions)
  (:types crate truck - object heavy - crate)
  (:constants dock - object)
  (:predicates (at ?c - crate ?p - object) (in ?c - crate ?t - truck) (loaded ?t - truck)
               (sealed ?c - crate) (ready))
  (:task deliver :parameters (?c - crate))
  (:method by-truck
    :parameters (?c - crate ?t - truck ?from - object)
    :task (deliver ?c)
    :precondition (not (sealed ?c))
    :ordered-subtasks (and (load ?c ?t ?from) (unload-all ?t)))
  (:action load
    :parameters (?c - crate ?t - truck ?p - object)
    :precondition (and (at ?c ?p) (not (loaded ?t)))
    :effect (and (not (at ?c ?p)) (in ?c ?t) (loaded ?t)))
  (:action unload-all
    :parameters (?t - truck)
    :precondition (forall (?c - crate) (not (sealed ?c)))
    :effect (and (forall (?c - crate) (when (in ?c ?t) (and (not (in ?c ?t)) (at ?c dock))))
                 (not (loaded ?t)) (not (ready)) (ready)))
)
"""

DEPOT_PROBLEM = """\
(define (problem p) (:domain depot)
  (:objects yard - object big - heavy small - crate t1 t2 - truck)
  (:htn :ordered-subtasks (and (deliver big) (deliver small)))
  (:init (at big yard) (at small yard) (loaded t1))
  (:goal (and (at big dock) (at small dock) (not (in big t2)))))
"""


def _solve(write, domain: str, problem: str, budget_ms: float = 5_000):
    loaded = load_hddl(write("domain.hddl", domain), write("problem.hddl", problem))
    return loaded, plan(loaded, budget_ms, first=True)


def test_types_constants_free_variables_forall_and_conditional_effects(write):
    problem, result = _solve(write, DEPOT, DEPOT_PROBLEM)
    assert result.plan is not None, result.explain()
    # ?t and ?from are bound from the facts the first subtask needs: t1 is loaded, so t2.
    assert [str(a) for a in result.plan.actions] == [
        "load(big, t2, yard)", "unload-all(t2)", "load(small, t2, yard)", "unload-all(t2)"]
    assert validate(problem, result.plan) == []
    assert problem.is_a("big", "crate") and not problem.is_a("t1", "crate")
    assert {a.agent for a in result.plan.actions} == {"agent"}
    assert "(in big t2)" in {link.fact for link in result.plan.links}


def test_links_are_derived_when_first_read_from_the_state_the_search_started_from(write):
    problem, result = _solve(write, DEPOT, DEPOT_PROBLEM)
    # One agent and no rules: the score needs no replay, so the plan replays when asked.
    assert result.plan.relate is not None
    problem.initial.clear()
    assert [(k.producer, k.consumer, k.fact) for k in result.plan.links] == [
        (0, 1, "(in big t2)"), (1, 2, "(loaded t2)"), (1, 3, "(in big t2)"),
        (2, 3, "(in small t2)")]
    assert result.plan.orderings == [(0, 1), (1, 2), (1, 3), (2, 3)]
    assert result.plan.relate is None


def test_deletions_come_before_additions(write):
    problem, result = _solve(write, DEPOT, DEPOT_PROBLEM)
    # unload-all deletes (ready) and adds it: PDDL applies deletions first, so it holds.
    final = dict(problem.initial)
    writes: list = []
    for action in result.plan.actions:
        env = dict(zip(problem.domain.actions[action.name].names, action.args, strict=True))
        writes.clear()
        problem.domain.actions[action.name].apply(
            env, lambda e, a: final.get((e, a)), lambda e, a, v: writes.append(((e, a), v)))
        final.update(writes)
    assert final.get(("ready", ())) is True
    assert final.get(("loaded", ("t2",))) is None
    assert final.get(("at", ("big", "dock"))) is True


def test_the_validator_refuses_a_binding_of_the_wrong_type(write):
    problem, result = _solve(write, DEPOT, DEPOT_PROBLEM)
    tree = result.plan.tree
    node = next(n for n in tree.values() if n.decomposition == "by-truck")
    node.bindings["?t"] = "big"
    errors = validate(problem, result.plan)
    assert any("variable ?t is bound to 'big', not a truck" in e for e in errors)


def test_the_validator_refuses_a_binding_that_does_not_match_the_task(write):
    problem, result = _solve(write, DEPOT, DEPOT_PROBLEM)
    node = next(n for n in result.plan.tree.values() if n.decomposition == "by-truck")
    node.bindings["?c"] = "small" if node.args == ("big",) else "big"
    errors = validate(problem, result.plan)
    assert any("precondition is false: task (deliver ?c)" in e for e in errors)


GUARD = """\
(define (domain guard)
  (:requirements :hierarchy :negative-preconditions)
  (:predicates (kept) (spent) (done))
  (:task step :parameters ())
  (:task finish :parameters ())
  (:method spend :parameters () :task (step) :ordered-subtasks (and (use)))
  (:method save :parameters () :task (step) :ordered-subtasks (and (skip)))
  (:method close :parameters () :task (finish) :ordered-subtasks (and (end)))
  (:action use :parameters () :effect (and (not (kept)) (spent)))
  (:action skip :parameters () :effect (and))
  (:action end :parameters () :effect (done)))
"""


def test_goal_protection_abandons_a_branch_where_a_goal_is_deleted_for_good(write):
    problem, result = _solve(write, GUARD, """\
        (define (problem p) (:domain guard)
          (:htn :ordered-subtasks (and (step) (finish)))
          (:init (kept)) (:goal (and (kept) (done))))
        """)
    assert [str(a) for a in result.plan.actions] == ["skip()", "end()"]
    assert validate(problem, result.plan) == []


def test_goal_protection_explains_why_no_plan_exists(write):
    problem, result = _solve(write, GUARD.replace("(:action skip :parameters () :effect (and))",
                                                  "(:action skip :parameters () "
                                                  ":effect (not (kept)))"), """\
        (define (problem p) (:domain guard)
          (:htn :ordered-subtasks (and (step) (finish)))
          (:init (kept)) (:goal (and (kept) (done))))
        """)
    assert result.plan is None
    assert "deletes (kept), a goal that no task left can make true again" in result.explain()


def test_a_negative_goal_must_hold_at_the_end(write):
    problem, result = _solve(write, GUARD, """\
        (define (problem p) (:domain guard)
          (:htn :ordered-subtasks (and (step)))
          (:init (kept)) (:goal (not (spent))))
        """)
    assert [str(a) for a in result.plan.actions] == ["skip()"]


LOOP = """\
(define (domain loop)
  (:requirements :hierarchy)
  (:predicates (done))
  (:task t :parameters ())
  (:method again :parameters () :task (t) :ordered-subtasks (and (t) (work)))
  (:method base :parameters () :task (t) :ordered-subtasks (and (rest)))
  (:action work :parameters () :effect (done))
  (:action rest :parameters () :effect (and)))
"""


def test_left_recursion_is_cut_then_deepened_when_a_plan_needs_it(write):
    problem, result = _solve(write, LOOP, """\
        (define (problem p) (:domain loop)
          (:htn :ordered-subtasks (and (t))) (:goal (done)))
        """)
    assert [str(a) for a in result.plan.actions] == ["rest()", "work()"]
    assert validate(problem, result.plan) == []


def test_left_recursion_alone_ends_the_search(write):
    problem, result = _solve(write, LOOP.replace(
        "(:method base :parameters () :task (t) :ordered-subtasks (and (rest)))", ""), """\
        (define (problem p) (:domain loop) (:htn :ordered-subtasks (and (t))))
        """, budget_ms=2_000)
    assert result.plan is None
    assert "left recursion" in result.explain()


def test_an_initial_task_network_with_parameters_has_them_bound(write):
    problem, result = _solve(write, DEPOT, """\
        (define (problem p) (:domain depot)
          (:objects yard - object big - heavy small - crate t1 t2 - truck)
          (:htn :parameters (?c - crate) :ordered-subtasks (and (deliver ?c)))
          (:init (at big yard) (at small yard)) (:goal (at small dock)))
        """)
    assert [str(a) for a in result.plan.actions] == ["load(small, t1, yard)",
                                                     "unload-all(t1)"]
    assert validate(problem, result.plan) == []
    root = result.plan.tree[result.plan.roots[0]]
    assert (root.task, root.bindings) == (":htn", {"?c": "small"})
    lines = write_ipc(result.plan).splitlines()
    assert lines[3] == "root 2" and lines[4] == "2 deliver small -> by-truck 0 1"
    assert ":htn" not in write_ipc(result.plan)


def test_a_goal_that_is_not_a_conjunction_of_literals_is_refused_at_its_position(write):
    with pytest.raises(FileError) as caught:
        _solve(write, GUARD, """\
            (define (problem p) (:domain guard)
              (:htn :ordered-subtasks (and (step)))
              (:goal (and (kept) (or (done) (spent)))))
            """)
    (found,) = caught.value.problems
    assert (found.line, found.col) == (3, 22)
    assert "goal 'or' is not supported" in found.message


def test_partial_order_is_refused_by_name(write):
    with pytest.raises(FileError) as caught:
        _solve(write, GUARD.replace(
            "(:method close :parameters () :task (finish) :ordered-subtasks (and (end)))",
            "(:method close :parameters () :task (finish) :subtasks (and (end) (end)))"),
            "(define (problem p) (:domain guard) (:htn :ordered-subtasks (and (finish))))")
    assert "not totally ordered" in caught.value.problems[0].message


def test_ipc_round_trip_keeps_the_tree(write):
    problem, result = _solve(write, DEPOT, DEPOT_PROBLEM)
    text = write_ipc(result.plan)
    assert text.splitlines()[5] == "root 4 5"
    assert shape(read_ipc(text)) == (
        (("load", ("big", "t2", "yard")), ("unload-all", ("t2",)),
         ("load", ("small", "t2", "yard")), ("unload-all", ("t2",))),
        (("deliver", ("big",), "by-truck", (("load", ("big", "t2", "yard")),
                                            ("unload-all", ("t2",)))),
         ("deliver", ("small",), "by-truck", (("load", ("small", "t2", "yard")),
                                              ("unload-all", ("t2",))))))


def test_ipc_reader_reports_bad_lines_with_their_position():
    with pytest.raises(FileError) as caught:
        read_ipc("==>\n0 noop\nroot x\n1 task1 donothing\n<==\n", "plan.txt")
    assert [(p.line, p.col) for p in caught.value.problems] == [(3, 1), (4, 1)]


def test_hatp_problems_keep_their_own_semantics():
    from planner import load_domain, load_problem

    domain = load_domain("living-room")
    problem = load_problem("planner/problems/clean-up.yaml", domain)
    assert not domain.predicates and all(a.agent for a in domain.actions.values())
    result = plan(dataclasses.replace(problem), 500)
    assert result.plan is not None and validate(problem, result.plan) == []


SORTS = """\
(define (domain sorts)
  (:requirements :typing :hierarchy)
  (:types small - item)
  (:predicates (free ?x - item))
  (:task pick :parameters ())
  (:method two
    :parameters (?x ?y - item)
    :task (pick)
    :constraints (and (sortof ?x - small) (not (= ?x ?y)))
    :ordered-subtasks (and (take ?x ?y)))
  (:action take :parameters (?x ?y - item) :precondition (and (free ?x) (free ?y))))
"""


def test_method_constraints_narrow_types_and_separate_variables(write):
    problem, result = _solve(write, SORTS, """\
        (define (problem p) (:domain sorts)
          (:objects aa bb - item zz - small)
          (:htn :ordered-subtasks (and (pick)))
          (:init (free aa) (free zz)))
        """)
    # ?x must be a small (zz, though aa comes first) and ?y another item: aa.
    assert [str(a) for a in result.plan.actions] == ["take(zz, aa)"]
    assert validate(problem, result.plan) == []


def test_a_sortof_that_widens_a_type_is_refused_at_the_type(write):
    text = SORTS.replace("(sortof ?x - small)", "(sortof ?x - object)")
    with pytest.raises(FileError) as caught:
        _solve(write, text, "(define (problem p) (:domain sorts))")
    (found,) = caught.value.problems
    line = text.splitlines().index(next(t for t in text.splitlines() if "sortof" in t)) + 1
    assert (found.line, found.col) == (line, text.splitlines()[line - 1].index("object") + 1)
    assert found.message == "'object' is not a subtype of ?x's type 'item'"


# ---------------------------------------------------------------- the total-order fragment

FRAGMENT = """\
(define (domain yard)
  (:requirements :typing :hierarchy :negative-preconditions :equality :conditional-effects
                 :universal-preconditions :method-preconditions)
  (:types place - object crate - object small - crate)
  (:predicates (at ?c - crate ?p - place) (road ?a ?b - place) (free ?p - place)
               (moved ?c - crate) (tidy))
  (:task carry :parameters (?c - crate ?to - place) :precondition () :effect ())
  (:task sweep :parameters ())
  (:method already-there
    :parameters (?c - crate ?to - place)
    :task (carry ?c ?to)
    :precondition (at ?c ?to)
    :ordered-subtasks ())
  (:method one-step
    :parameters (?c - crate ?from ?to - place)
    :task (carry ?c ?to)
    :constraints (and (not (= ?from ?to)))
    :ordered-subtasks (and (push ?c ?from ?to)))
  (:method two-steps
    :parameters (?c - crate ?from ?via ?to - place)
    :task (carry ?c ?to)
    :constraints (and (not (= ?via ?to)) (sortof ?c - small))
    :ordered-subtasks (and (push ?c ?from ?via) (push ?c ?via ?to)))
  (:method sweep-all
    :parameters ()
    :task (sweep)
    :precondition (forall (?c - crate) (moved ?c))
    :ordered-subtasks (and (clean)))
  (:action push
    :parameters (?c - crate ?a ?b - place)
    :precondition (and (at ?c ?a) (road ?a ?b) (not (= ?a ?b)))
    :effect (and (not (at ?c ?a)) (at ?c ?b) (moved ?c)))
  (:action clean
    :parameters ()
    :precondition ()
    :effect (and (forall (?p - place) (when (free ?p) (tidy)))))
)
"""

FRAGMENT_PROBLEM = """\
(define (problem p) (:domain yard)
  (:objects a b c d - place box - crate pebble - small)
  (:htn :parameters (?dest - place)
        :ordered-subtasks (and (carry box ?dest) (carry pebble ?dest) (sweep))
        :constraints (and (= ?dest c)))
  (:init (at box a) (at pebble b) (road a c) (road b d) (road d c) (free d))
  (:goal (and (at box c) (tidy))))
"""


def test_every_construct_of_the_fragment_plans_and_validates(write):
    """Method variables bound only through subtasks (?from, ?via: the static roads of the
    second push), ':constraints' in methods and in ':htn' ('=', 'not =', 'sortof'),
    abstract tasks with empty bodies, forall/when effects, a forall precondition."""
    problem, result = _solve(write, FRAGMENT, FRAGMENT_PROBLEM)
    assert result.plan is not None, result.explain()
    assert [str(a) for a in result.plan.actions] == [
        "push(box, a, c)", "push(pebble, b, d)", "push(pebble, d, c)", "clean()"]
    assert validate(problem, result.plan) == []
    tree = result.plan.tree
    assert [tree[c].decomposition for c in tree[result.plan.roots[0]].children] == [
        "one-step", "two-steps", "sweep-all"]


def test_sortof_in_a_method_keeps_other_kinds_out(write):
    # box is a crate but not a small: two-steps is not for it, and one step cannot do.
    problem, result = _solve(write, FRAGMENT, FRAGMENT_PROBLEM.replace(
        "(at box a) (at pebble b)", "(at box b) (at pebble a)").replace(
        "(carry box ?dest) (carry pebble ?dest)", "(carry box ?dest)"))
    assert result.plan is None
    assert "two-steps" in result.explain()


def test_an_equality_constraint_in_the_initial_network_binds_its_parameter(write):
    problem, result = _solve(write, FRAGMENT, FRAGMENT_PROBLEM.replace("(= ?dest c)",
                                                                     "(= ?dest d)").replace(
        "(:goal (and (at box c) (tidy)))", ""))
    assert result.plan is None  # the box cannot reach d
    problem, result = _solve(write, FRAGMENT, FRAGMENT_PROBLEM.replace(
        "(carry box ?dest) (carry pebble ?dest) (sweep)", "(carry pebble ?dest)").replace(
        "(= ?dest c)", "(= ?dest d)").replace("(:goal (and (at box c) (tidy)))", ""))
    assert [str(a) for a in result.plan.actions] == ["push(pebble, b, d)"]
    assert validate(problem, result.plan) == []
    assert "?dest" not in write_ipc(result.plan)


def test_a_negated_condition_of_the_first_action_on_parameters_left_free(write):
    """Regression: the binder tested '(not (clear ?x))' of the first action with every
    parameter of that action renamed, bound or not (KeyError: '?y')."""
    domain = """\
        (define (domain d) (:requirements :typing :hierarchy :negative-preconditions)
          (:types block)
          (:predicates (on ?x ?y - block) (clear ?x - block))
          (:task t :parameters (?x - block))
          (:method m :parameters (?x ?y ?z - block) :task (t ?x)
            :ordered-subtasks (and (a ?x ?y ?z)))
          (:action a :parameters (?x ?y ?z - block)
            :precondition (and (not (clear ?x)) (on ?x ?y) (on ?y ?z)
                               (forall (?w - block) (not (on ?w ?x))))
            :effect (clear ?x)))
        """
    problem, result = _solve(write, domain, """\
        (define (problem p) (:domain d) (:objects b1 b2 b3 - block)
          (:htn :ordered-subtasks (and (t b1))) (:init (on b1 b2) (on b2 b3))
          (:goal (clear b1)))
        """)
    assert [str(a) for a in result.plan.actions] == ["a(b1, b2, b3)"]
    assert validate(problem, result.plan) == []


def test_method_preconditions_read_the_state_the_method_is_entered_in(write):
    domain = """\
        (define (domain d) (:requirements :hierarchy :negative-preconditions)
          (:predicates (lit) (seen))
          (:task t :parameters ())
          (:method when-dark :parameters () :task (t) :precondition (not (lit))
            :ordered-subtasks (and (switch) (look)))
          (:method when-lit :parameters () :task (t) :precondition (lit)
            :ordered-subtasks (and (look)))
          (:action switch :parameters () :precondition (not (lit)) :effect (lit))
          (:action look :parameters () :precondition (lit) :effect (seen)))
        """
    problem, result = _solve(write, domain, """\
        (define (problem p) (:domain d) (:htn :ordered-subtasks (and (t) (t))) (:goal (seen)))
        """)
    assert [str(a) for a in result.plan.actions] == ["switch()", "look()", "look()"]
    tree = result.plan.tree
    assert [tree[r].decomposition for r in result.plan.roots] == ["when-dark", "when-lit"]
    assert validate(problem, result.plan) == []


def test_an_abstract_task_with_a_real_precondition_is_refused_at_the_keyword(write):
    with pytest.raises(FileError) as caught:
        load_hddl(write("d.hddl", FRAGMENT.replace(
            "(:task sweep :parameters ())", "(:task sweep :parameters () :effect (tidy))")),
            write("p.hddl", FRAGMENT_PROBLEM))
    (found,) = caught.value.problems
    assert (found.line, found.col) == (8, 31)
    assert "abstract tasks with effects" in found.message

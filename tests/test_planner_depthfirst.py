"""The depth-first first-plan search (planner/search/depthfirst.py): what it prunes, its budgets."""

from __future__ import annotations

import pytest
from chores import CHORES, chores_problem, plans_with_checks

from planner import load_hddl, plan, validate
from planner.search import depthfirst
from planner.search.depthfirst import BUDGET_EXHAUSTED, first_plan

WALK = """\
(define (domain walk) (:requirements :typing :hierarchy :negative-preconditions :equality)
  (:types cell)
  (:predicates (at ?c - cell) (next ?a ?b - cell) (cheese ?c - cell) (fed))
  (:task go :parameters (?to - cell))
  (:task eat :parameters ())
  (:method arrived :parameters (?to - cell) :task (go ?to) :precondition (at ?to)
    :ordered-subtasks ())
  (:method step :parameters (?to ?from ?by - cell) :task (go ?to)
    :precondition (and (at ?from) (not (= ?from ?to)))
    :ordered-subtasks (and (move ?from ?by) (go ?to)))
  (:method eat-here :parameters (?c - cell) :task (eat) :precondition (cheese ?c)
    :ordered-subtasks (and (go ?c) (nibble ?c)))
  (:action move :parameters (?a ?b - cell) :precondition (and (at ?a) (next ?a ?b))
    :effect (and (not (at ?a)) (at ?b)))
  (:action nibble :parameters (?c - cell) :precondition (and (at ?c) (cheese ?c))
    :effect (and (fed) (not (cheese ?c)))))
"""


def _ring(size: int, cheese: int) -> str:
    cells = " ".join(f"c{i}" for i in range(size))
    links = " ".join(f"(next c{i} c{(i + 1) % size}) (next c{(i + 1) % size} c{i})"
                     for i in range(size))
    return (f"(define (problem p) (:domain walk) (:objects {cells} - cell)\n"
            f"  (:htn :ordered-subtasks (and (eat)))\n"
            f"  (:init (at c0) (cheese c{cheese}) {links})\n  (:goal (fed)))\n")


def test_a_tail_recursive_walk_ends_because_a_node_is_not_expanded_twice(write):
    problem = load_hddl(write("d.hddl", WALK), write("p.hddl", _ring(12, 6)))
    result = first_plan(problem, 10_000)
    assert result.plan is not None, result.explain()
    assert result.first and result.plans_found == 1
    assert validate(problem, result.plan) == []
    assert result.plan.actions[-1].name == "nibble"
    # Without the check a walk back and forth between c0 and c1 never ends.
    assert result.expansions < 2_000


def test_no_cheese_reachable_ends_with_the_whole_space_searched(write):
    ring = _ring(8, 3).replace("(next c2 c3) (next c3 c2) ", "").replace(
        "(next c3 c4) (next c4 c3) ", "")
    problem = load_hddl(write("d.hddl", WALK), write("p.hddl", ring))
    result = first_plan(problem, 10_000)
    assert result.plan is None and result.complete
    assert "searched before, in this very state (a loop)" in result.explain()


SWITCH = """\
(define (domain switch) (:requirements :hierarchy :negative-preconditions)
  (:predicates (on) (power) (done))
  (:task ready :parameters ())
  (:task work :parameters ())
  (:method cycle :parameters () :task (ready) :precondition (on)
    :ordered-subtasks (and (off) (turn-on) (ready) (note)))
  (:method already :parameters () :task (ready) :precondition (on)
    :ordered-subtasks ())
  (:method start :parameters () :task (work) :ordered-subtasks (and (ready) (finish)))
  (:action off :parameters () :precondition (on) :effect (and (not (on)) (power)))
  (:action turn-on :parameters () :precondition (power) :effect (and (on) (not (power))))
  (:action note :parameters () :precondition () :effect ())
  (:action finish :parameters () :precondition (on) :effect (done)))
"""


def test_a_decomposition_repeated_in_the_same_state_is_cut(write):
    """Satellite's shape: the first method switches off and on to decompose the same task
    again, in the same state, with more to do after it each time (so no node repeats,
    and without the cut the search goes down forever); the cut sends the search back to
    the outer task's second method."""
    problem = load_hddl(write("d.hddl", SWITCH), write("p.hddl", """\
        (define (problem p) (:domain switch) (:htn :ordered-subtasks (and (work)))
          (:init (on)) (:goal (done)))
        """))
    result = first_plan(problem, 10_000)
    assert result.plan is not None, result.explain()
    assert [str(a) for a in result.plan.actions] == ["finish()"]
    assert [result.plan.tree[c].decomposition
            for c in result.plan.tree[result.plan.roots[0]].children] == ["already", None]
    assert result.expansions < 50
    assert validate(problem, result.plan) == []


COUNTER = """\
(define (domain count) (:requirements :typing :hierarchy :negative-preconditions)
  (:types bit)
  (:predicates (on ?b - bit) (never))
  (:task t :parameters ())
  (:method flip :parameters (?b - bit) :task (t) :ordered-subtasks (and (set ?b) (t)))
  (:method unflip :parameters (?b - bit) :task (t) :ordered-subtasks (and (reset ?b) (t)))
  (:action set :parameters (?b - bit) :precondition (not (on ?b)) :effect (on ?b))
  (:action reset :parameters (?b - bit) :precondition (on ?b) :effect (not (on ?b))))
"""


def _counter(write, bits: int = 30):
    objects = " ".join(f"b{i}" for i in range(bits))
    return load_hddl(write("d.hddl", COUNTER), write("p.hddl", (
        f"(define (problem p) (:domain count) (:objects {objects} - bit)\n"
        "  (:htn :ordered-subtasks (and (t))))\n")))


def test_a_recursion_through_ever_new_states_ends_at_the_node_budget(write):
    result = first_plan(_counter(write), 60_000, max_nodes=3_000)
    assert result.plan is None and not result.complete
    assert result.expansions == 3_000
    assert result.explain().startswith(
        f"{BUDGET_EXHAUSTED}: the node budget (3000) ran out after 3000 search nodes")


def test_a_branch_deeper_than_the_limit_is_cut_and_said_so(write, monkeypatch):
    monkeypatch.setattr(depthfirst, "MAX_DEPTH", 40)
    monkeypatch.setattr(depthfirst, "DEEPEST", 40)  # no deeper pass after the cut
    result = first_plan(_counter(write, 6), 60_000)
    assert result.plan is None
    text = result.explain()
    assert text.startswith(f"{BUDGET_EXHAUSTED}: branches deeper than 40 decompositions")
    assert "more) ..." in text  # a 40-task path is shortened in the explanation


def test_the_time_budget_is_a_search_budget_too(write):
    result = first_plan(_counter(write), 200)
    assert result.plan is None and not result.complete
    assert result.explain().startswith(f"{BUDGET_EXHAUSTED}: the time budget (200 ms)")


def test_first_plan_mode_of_an_hddl_problem_is_this_search(write, monkeypatch):
    problem = load_hddl(write("d.hddl", WALK), write("p.hddl", _ring(6, 3)))
    seen = []
    real = depthfirst.DepthFirst.run

    def spy(self, *args, **kwargs):
        seen.append(self.problem.name)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(depthfirst.DepthFirst, "run", spy)
    improved = []
    result = plan(problem, 5_000, improved.append, first=True)
    assert seen == ["p"] and improved == [result.plan]
    improved.clear()
    better = plan(problem, 2_000, improved.append)  # anytime: this search, then the other
    assert seen == ["p", "p"] and improved[0].score >= better.plan.score == improved[-1].score
    assert validate(problem, better.plan) == []


@pytest.mark.parametrize("bits", [12])
def test_the_command_says_the_budget_ran_out_and_exits_1(shary, write, bits):
    objects = " ".join(f"b{i}" for i in range(bits))
    domain = write("d.hddl", COUNTER)
    problem = write("p.hddl", f"(define (problem p) (:domain count) (:objects {objects} - bit)"
                              " (:htn :ordered-subtasks (and (t))))\n")
    status, out, err = shary("plan", "--hddl", domain, problem, "--budget-ms", "300")
    assert status == 1
    assert "no plan" in out and BUDGET_EXHAUSTED in out
    status, out, err = shary("plan", "--hddl", domain, problem, "--budget-ms", "300", "--ipc")
    assert status == 1 and out == ""
    assert "no plan" in err and BUDGET_EXHAUSTED in err


def test_the_command_improves_on_the_first_plan_only_when_asked(shary, write):
    domain, problem = write("d.hddl", WALK), write("p.hddl", _ring(8, 3))
    status, out, err = shary("plan", "--hddl", domain, problem)
    assert status == 0 and "1 plan(s)" in out and "first plan" in out
    status, out, err = shary("plan", "--hddl", domain, problem, "--improve",
                             "--budget-ms", "1500")
    assert status == 0, err
    assert "first plan" not in out and "validated" in out


PLOTS = """\
(define (domain plots) (:requirements :typing :hierarchy :negative-preconditions)
  (:types plot - object bit - plot)
  (:predicates (free ?p - plot) (shed ?p - plot) (house ?p - plot) (on ?b - bit)
               (next ?a ?b - bit) (last ?b - bit))
  (:task settle :parameters (?p - plot))
  (:task chores :parameters (?b - bit))
  (:method build :parameters (?p ?s - plot ?b - bit) :task (settle ?p)
    :precondition (and (last ?b))
    :ordered-subtasks (and (put-shed ?s) (chores ?b) (put-house ?p)))
  (:method built :parameters (?p - plot) :task (settle ?p) :precondition (house ?p)
    :ordered-subtasks ())
  (:method work :parameters (?b ?n - bit) :task (chores ?b) :precondition (next ?b ?n)
    :ordered-subtasks (and (set ?b) (chores ?n)))
  (:method rest :parameters (?b ?n - bit) :task (chores ?b) :precondition (next ?b ?n)
    :ordered-subtasks (chores ?n))
  (:method stop :parameters (?b - bit) :task (chores ?b) :ordered-subtasks ())
  (:action put-shed :parameters (?s - plot) :precondition (free ?s)
    :effect (and (not (free ?s)) (shed ?s)))
  (:action put-house :parameters (?p - plot) :precondition (free ?p)
    :effect (and (not (free ?p)) (house ?p)))
  (:action set :parameters (?b - bit) :precondition (not (on ?b))
    :effect (and (on ?b) (not (free ?b)))))
"""


def _plots(write, init: str, bits: int = 18):
    objects = " ".join(f"b{i}" for i in range(bits))
    chain = " ".join(f"(next b{i} b{i + 1})" for i in range(bits - 1))
    return load_hddl(write("d.hddl", PLOTS), write("p.hddl", (
        f"(define (problem p) (:domain plots) (:objects a z - plot {objects} - bit)\n"
        "  (:htn :ordered-subtasks (and (settle a)))\n"
        f"  (:init {init} {chain} (last b0)))\n")))


def test_a_step_that_deletes_what_a_later_action_needs_dooms_its_decomposition(write, monkeypatch):
    """Factories' shape: the shed may go on the plot the house needs later (``?s = a``,
    first in name order), and the chores in between have 2^18 ways that all end at
    the house that cannot be built: the decomposition is refused where it is chosen,
    because nothing between the shed and the house can free the plot again."""
    monkeypatch.setattr(depthfirst, "PLAIN_NODES", 1_000)  # the checks start after
    result = first_plan(_plots(write, "(free a) (free z)"), 60_000, max_nodes=20_000)
    assert result.plan is not None, result.explain()
    assert [str(a) for a in result.plan.actions][::len(result.plan.actions) - 1] == [
        "put-shed(z)", "put-house(a)"]
    assert validate(_plots(write, "(free a) (free z)"), result.plan) == []


def test_an_action_needing_a_false_fact_no_earlier_task_adds_dooms_its_decomposition(
        write, monkeypatch):
    """The house is built already (plot ``a`` not free): ``build`` (tried first) would
    run every way of doing the chores (which delete facts of the same predicate, so the
    binder cannot check ``(free a)`` on entry) before its last step fails."""
    monkeypatch.setattr(depthfirst, "PLAIN_NODES", 1_000)  # the checks start after
    problem = _plots(write, "(house a) (free z)")
    result = first_plan(problem, 60_000, max_nodes=20_000)
    assert result.plan is not None, result.explain()
    assert list(result.plan.actions) == []
    assert [result.plan.tree[r].decomposition for r in result.plan.roots] == ["built"]


STOCK = """\
(define (domain stock) (:requirements :typing :hierarchy :negative-preconditions)
  (:types pile bit)
  (:constants a - pile)
  (:predicates (stock ?p - pile) (spare ?p - pile) (got) (on ?b - bit)
               (next ?a ?b - bit) (last ?b - bit))
  (:task settle :parameters ())
  (:task chores :parameters (?b - bit))
  (:method build :parameters (?s - pile ?b - bit) :task (settle) :precondition (last ?b)
    :ordered-subtasks (and (take ?s) (chores ?b) (use a)))
  (:method fill :parameters (?b ?n - bit ?p - pile) :task (chores ?b)
    :precondition (and (next ?b ?n) (spare ?p)) :ordered-subtasks (and (restock ?p) (chores ?n)))
""" + CHORES + """\
  (:action take :parameters (?s - pile) :precondition (stock ?s)
    :effect (and (not (stock ?s)) (got)))
  (:action use :parameters (?p - pile) :precondition (and (stock ?p) (got)) :effect ())
  (:action restock :parameters (?p - pile) :precondition (spare ?p) :effect (stock ?p)))
"""


def test_a_step_that_deletes_what_a_later_action_needs_is_tried_after_the_others(
        write, monkeypatch):
    """Factories' resources: ``take a`` empties the pile that ``use a`` needs at the end;
    a chore in between may restock a pile (so the threat is not proved, and
    the decomposition is not refused), but only ``z`` is ever restocked.  ``take a`` comes
    first in the binder's order, and every way of doing the chores would be tried
    before ``use a`` fails: the bindings that threaten a fact a later action needs are
    tried after the others."""
    monkeypatch.setattr(depthfirst, "PLAIN_NODES", 1_000)  # the checks start after
    objects = " ".join(f"b{i}" for i in range(18))
    chain = " ".join(f"(next b{i} b{i + 1})" for i in range(17))
    problem = load_hddl(write("d.hddl", STOCK), write("p.hddl", (
        f"(define (problem p) (:domain stock) (:objects z - pile {objects} - bit)\n"
        "  (:htn :ordered-subtasks (and (settle)))\n"
        f"  (:init (stock a) (stock z) (spare z) {chain} (last b0)))\n")))
    result = first_plan(problem, 60_000, max_nodes=20_000)
    assert result.plan is not None, result.explain()
    assert [str(a) for a in result.plan.actions][::len(result.plan.actions) - 1] == [
        "take(z)", "use(a)"]
    assert validate(problem, result.plan) == []


WATCH = """\
(define (domain watch) (:requirements :typing :hierarchy :negative-preconditions :equality)
  (:types bit agent)
  (:constants ann bob - agent)
  (:predicates (on ?b - bit) (next ?a ?b - bit) (ready) (seen))
  (:task top :parameters ())
  (:task chores :parameters (?b - bit))
  (:task act :parameters (?who - agent))
  (:method busy :parameters (?b - bit) :task (top) :precondition (first ?b)
    :ordered-subtasks (and (chores ?b) (act bob)))
  (:method watched :parameters (?who - agent) :task (top)
    :ordered-subtasks (and (prepare) (act ?who)))
  (:method observed :parameters (?who - agent) :task (act ?who)
    :precondition (= ?who ann) :ordered-subtasks (observe))
  (:method plain :parameters (?who - agent) :task (act ?who) :ordered-subtasks ())
""" + CHORES + """\
  (:action prepare :parameters () :precondition () :effect (ready))
  (:action observe :parameters () :precondition (ready) :effect (seen)))
"""


def _watch(write):
    domain = WATCH.replace("(:predicates", "(:predicates (first ?b - bit)")
    return chores_problem(write, domain, "(seen)")


def test_what_a_task_may_add_is_guarded_by_the_constants_its_methods_require(write):
    domain = _watch(write).domain
    assert domain.may_add("act", ("ann",), "seen", ())
    assert not domain.may_add("act", ("bob",), "seen", ())  # only 'observed' adds it


def test_a_decomposition_leaving_no_task_able_to_reach_the_goal_is_refused(write, monkeypatch):
    """Monroe's plan recognition: ``busy`` (tried first) does 2^18 chores and then acts
    as ``bob``, who cannot observe; refused where it is chosen."""
    plans_with_checks(_watch(write), monkeypatch, ["prepare()", "observe()"])

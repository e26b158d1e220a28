"""The goal-guided best-first search (planner/search/progression.py) and the IPC mode's portfolio
(planner/search/portfolio.py): what the depth-first search cannot do within a node budget."""

from __future__ import annotations

import math

from planner import load_hddl, plan, validate
from planner.io.ipc import read_ipc, write_ipc
from planner.search import depthfirst, portfolio
from planner.search.progression import best_first, least_work

LIGHTS = """\
(define (domain lights) (:requirements :typing :hierarchy :negative-preconditions)
  (:types light)
  (:predicates (on ?l - light))
  (:task fiddle :parameters ())
  (:task switch :parameters (?l - light))
  (:method enough :parameters () :task (fiddle) :ordered-subtasks ())
  (:method flip :parameters (?l - light) :task (fiddle)
    :ordered-subtasks (and (switch ?l) (fiddle)))
  (:method turn-on :parameters (?l - light) :task (switch ?l)
    :precondition (not (on ?l)) :ordered-subtasks (and (light-up ?l)))
  (:method turn-off :parameters (?l - light) :task (switch ?l)
    :precondition (on ?l) :ordered-subtasks (and (put-out ?l)))
  (:action light-up :parameters (?l - light) :precondition (not (on ?l)) :effect (on ?l))
  (:action put-out :parameters (?l - light) :precondition (on ?l) :effect (not (on ?l))))
"""


def _lights(count: int, wanted: list[int]) -> str:
    names = " ".join(f"l{i:02d}" for i in range(count))
    goal = " ".join(f"(on l{i:02d})" for i in wanted)
    return (f"(define (problem p) (:domain lights) (:objects {names} - light)\n"
            f"  (:htn :ordered-subtasks (and (fiddle)))\n  (:init)\n"
            f"  (:goal (and {goal})))\n")


def test_the_least_work_of_a_task_is_the_fewest_actions_it_can_end_in(write):
    problem = load_hddl(write("d.hddl", LIGHTS), write("p.hddl", _lights(3, [1])))
    work = least_work(problem)
    assert work["fiddle"] == 0 and work["switch"] == 1 and work["light-up"] == 1
    broken = LIGHTS.replace("(:method enough :parameters () :task (fiddle) "
                            ":ordered-subtasks ())", "")
    problem = load_hddl(write("d2.hddl", broken), write("p2.hddl", _lights(3, [1])))
    assert least_work(problem)["fiddle"] == math.inf  # it never ends


def test_the_goal_guides_the_choice_that_depth_first_search_makes_in_file_order(write):
    # Depth-first takes the lights in name order: it lights l00, l01, ... and needs
    # every subset below the three lights wanted before it finds them.
    problem = load_hddl(write("d.hddl", LIGHTS), write("p.hddl", _lights(20, [17, 18, 19])))
    blind = depthfirst.first_plan(problem, 60_000, max_nodes=5_000)
    assert blind.plan is None
    result = best_first(problem, 60_000, max_nodes=5_000)
    assert result.plan is not None, result.explain()
    assert result.first and validate(problem, result.plan) == []
    assert sorted(a.args[0] for a in result.plan.actions) == ["l17", "l18", "l19"]


def test_the_portfolio_gives_the_best_first_search_what_depth_first_leaves(write):
    problem = load_hddl(write("d.hddl", LIGHTS), write("p.hddl", _lights(20, [17, 18, 19])))
    result = plan(problem, 60_000, first=True, max_nodes=5_000)
    assert result.plan is not None, result.explain()
    assert validate(problem, result.plan) == []
    # Where the depth-first search finds a plan, its plan is the portfolio's.
    easy = load_hddl(write("d.hddl", LIGHTS), write("e.hddl", _lights(20, [0])))
    ours = portfolio.first_plan(easy, 60_000)
    assert [a.args for a in ours.plan.actions] == [
        a.args for a in depthfirst.first_plan(easy, 60_000).plan.actions]


def test_a_search_that_ends_without_a_plan_names_the_goals_it_missed(write):
    impossible = LIGHTS.replace("(:action light-up :parameters (?l - light) :precondition "
                                "(not (on ?l)) :effect (on ?l))",
                                "(:action light-up :parameters (?l - light) :precondition "
                                "(not (on ?l)) :effect (not (on ?l)))")
    problem = load_hddl(write("d.hddl", impossible), write("p.hddl", _lights(4, [1])))
    result = best_first(problem, 60_000)
    assert result.plan is None and result.complete
    assert "ends without (on l01) == True" in result.explain()


NETWORK = """\
(define (problem p) (:domain lights) (:objects {names} - light)
  (:htn :parameters (?a ?b ?c ?d - light)
    :ordered-subtasks (and (switch ?a) (switch ?b) (switch ?c) (switch ?d)))
  (:init)
  (:goal (and (on l16) (on l17) (on l18) (on l19))))
"""


def test_the_networks_parameters_are_bound_when_their_task_comes_first(write):
    # Bound all at once, in name order, the four parameters have 20**4 = 160,000
    # values, and the ones that work come last; bound one task at a time, each is
    # chosen by the goal.
    names = " ".join(f"l{i:02d}" for i in range(20))
    problem = load_hddl(write("d.hddl", LIGHTS), write("p.hddl", NETWORK.format(names=names)))
    blind = depthfirst.first_plan(problem, 60_000, max_nodes=20_000)
    assert blind.plan is None
    result = best_first(problem, 60_000, max_nodes=20_000)
    assert result.plan is not None, result.explain()
    assert validate(problem, result.plan) == []
    written = read_ipc(write_ipc(result.plan, problem.spelling))
    assert sorted(written.actions[i][1][0] for i in written.actions) == [
        "l16", "l17", "l18", "l19"]
    # The network's task is left out of the IPC plan: its subtasks are the top tasks.
    assert len(written.roots) == 4

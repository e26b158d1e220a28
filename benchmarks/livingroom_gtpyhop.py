"""The living-room clean-up written in GTPyhop's style, for the planner's benchmark.

Actions and methods are Python functions over a ``gtpyhop.State`` whose
attributes are dicts (``state.at[agent]``), as GTPyhop's own examples write
them; each mirrors the YAML domain (``planner/domains/living-room.yaml``):
the same actions with the same preconditions and effects, the same methods
with their decompositions in the same order.  A method that binds a variable
(which bin, which helper) becomes one GTPyhop method per value, in name order,
since a GTPyhop method returns one list of subtasks and GTPyhop backtracks
over methods only.

What GTPyhop's model cannot express, and this translation leaves out: costs
(a plan is a list of actions; GTPyhop returns the first one it finds, with
no notion of a better plan), social rules (no penalty can be attached to a
sequence, a state, a decomposition, a wait or a link), AHP (no criteria),
several agents' streams (a plan is one sequence; who does what is only an
argument) and the causal links between them.  So it is compared with our
*first* plan only.
"""

from __future__ import annotations

import contextlib
import io
from typing import Any

import _first  # noqa: F401  (this folder after the packages: see _first.py)

from planner import Problem

with contextlib.redirect_stdout(io.StringIO()):  # GTPyhop prints as it loads
    import gtpyhop

DOMAIN_NAME = "living_room_clean_up"


def state_of(problem: Problem) -> Any:
    """GTPyhop's state for one of our living-room problems (its initial values)."""
    state = gtpyhop.State("living-room")
    state.at, state.carries, state.on, state.holder = {}, {}, {}, {}
    state.kind, state.move_cost, state.pick_cost, state.reach = {}, {}, {}, {}
    state.place, state.container, state.seat = {}, {}, {}
    for (entity, attribute), value in problem.initial.items():
        target = {"robot_reach": "reach"}.get(attribute, attribute)
        if hasattr(state, target) and isinstance(getattr(state, target), dict):
            getattr(state, target)[entity] = value
    for entity, kind in problem.entities.items():
        if kind == "Agent":
            state.carries.setdefault(entity, None)
        elif kind == "Object":
            state.holder.setdefault(entity, None)
    return state


def tasks_of(problem: Problem) -> list[tuple]:
    """The problem's top tasks as GTPyhop's todo list."""
    names = {"CleanUp": "clean_up"}
    return [(names[name], *args) for name, args in problem.tasks]


# -- actions --------------------------------------------------------------------------------


def move(s: Any, ag: str, to: str) -> Any:
    if s.at[ag] != to:
        s.at[ag] = to
        return s
    return False


def pick(s: Any, ag: str, obj: str, f: str) -> Any:
    if (s.on.get(obj) == f and s.at[ag] == s.place[f] and s.carries[ag] is None
            and (s.kind[ag] == "human" or s.reach[obj])):
        s.on[obj] = None
        s.holder[obj] = ag
        s.carries[ag] = obj
        return s
    return False


def put_down(s: Any, ag: str, obj: str, f: str) -> Any:
    if s.carries[ag] == obj and s.at[ag] == s.place[f] and not s.container[f]:
        s.holder[obj] = None
        s.on[obj] = f
        s.carries[ag] = None
        return s
    return False


def dump(s: Any, ag: str, obj: str, f: str) -> Any:
    if s.carries[ag] == obj and s.at[ag] == s.place[f] and s.container[f]:
        s.holder[obj] = None
        s.on[obj] = f
        s.carries[ag] = None
        return s
    return False


def give(s: Any, ag: str, to: str, obj: str) -> Any:
    if s.carries[ag] == obj and s.carries[to] is None and s.at[ag] == s.at[to] and ag != to:
        s.carries[ag] = None
        s.carries[to] = obj
        s.holder[obj] = to
        return s
    return False


# -- methods ----------------------------------------------------------------------------------


def goto_here(s: Any, ag: str, p: str) -> Any:
    return [] if s.at[ag] == p else False


def goto_move(s: Any, ag: str, p: str) -> Any:
    return [("move", ag, p)] if s.at[ag] != p else False


def fetch_direct_holding(s: Any, ag: str, obj: str) -> Any:
    return [] if s.holder[obj] == ag else False


def fetch_direct_pick(s: Any, ag: str, obj: str) -> Any:
    f = s.on.get(obj)  # the YAML method binds f to the furniture it is on: one value
    if f is None:
        return False
    return [("goto", ag, s.place[f]), ("pick", ag, obj, f)]


def fetch_direct(s: Any, ag: str, obj: str) -> Any:
    return [("fetch_direct", ag, obj)]


def fetch_helped(s: Any, ag: str, obj: str) -> Any:
    return [("ask_help", ag, obj)]


def _ask_help(helper: str) -> Any:
    def ask_help(s: Any, r: str, obj: str) -> Any:
        if s.kind[helper] == "human" and helper != r and s.carries[helper] is None:
            return [("fetch_direct", helper, obj), ("goto", helper, s.at[r]),
                    ("give", helper, r, obj)]
        return False

    ask_help.__name__ = f"ask_help_{helper.replace('-', '_')}"
    return ask_help


def _clean_up(kind: str, robot: str, furniture: str) -> Any:
    def clean_up(s: Any, obj: str) -> Any:
        if s.kind[robot] != "robot":
            return False
        if kind == "throw" and s.container[furniture]:
            return [("fetch", robot, obj), ("goto", robot, s.place[furniture]),
                    ("dump", robot, obj, furniture)]
        if (kind == "store" and not s.container[furniture] and not s.seat[furniture]
                and s.on.get(obj) != furniture):
            return [("fetch", robot, obj), ("goto", robot, s.place[furniture]),
                    ("put_down", robot, obj, furniture)]
        return False

    clean_up.__name__ = f"clean_up_{kind}_{robot}_{furniture}".replace("-", "_")
    return clean_up


def domain_for(problem: Problem) -> Any:
    """A GTPyhop domain for this problem's entities (the methods that bind variables
    become one method per value, in name order, as our search tries them)."""
    with contextlib.redirect_stdout(io.StringIO()):
        domain = gtpyhop.Domain(DOMAIN_NAME)
        gtpyhop.set_verbose_level(0)
    gtpyhop.declare_actions(move, pick, put_down, dump, give)
    gtpyhop.declare_task_methods("goto", goto_here, goto_move)
    gtpyhop.declare_task_methods("fetch_direct", fetch_direct_holding, fetch_direct_pick)
    gtpyhop.declare_task_methods("fetch", fetch_direct, fetch_helped)
    agents, furniture = problem.of_type("Agent"), problem.of_type("Furniture")
    gtpyhop.declare_task_methods("ask_help", *[_ask_help(h) for h in agents])
    gtpyhop.declare_task_methods(
        "clean_up", *[_clean_up(kind, r, f) for kind in ("throw", "store")
                      for r in agents for f in furniture])
    return domain


def find_plan(domain: Any, state: Any, todo: list[tuple]) -> Any:
    """GTPyhop's first plan (a list of action tuples) or False, from ``state`` (which it
    changes: pass a copy).  Its depth-first search with backtracking, iterative (its
    default commits to the first applicable method and never backtracks: it finds no
    plan once a bottle is out of the robot's reach)."""
    gtpyhop.set_current_domain(domain)
    with contextlib.redirect_stdout(io.StringIO()):
        gtpyhop.set_recursive_planning("iterative_dfs_backtracking")
        return gtpyhop.find_plan(state, todo)


if __name__ == "__main__":
    print("benchmarks/livingroom_gtpyhop.py: problems and helpers that "
          "benchmarks/planner.py and benchmarks/planner_vs_gtpyhop.py time; run that instead")

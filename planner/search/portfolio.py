"""The planner's entry, :func:`plan`, and the IPC mode's searches, one after the other
within one time budget.

A problem written in the planner's YAML is searched by the anytime branch and bound
(:mod:`planner.search.branchbound`); an HDDL problem by the searches below.

Depth-first decomposition (:mod:`planner.search.depthfirst`) is what most of the IPC
2020 total-order domains need: their hierarchy says what to do, and following
it in file order finds a plan of tens of thousands of actions in seconds (Towers,
Logistics, Elevator).  Where the hierarchy leaves the work to choices that only
the goal can tell apart (Multiarm-Blocksworld, Freecell), it wanders; the
greedy best-first search (:mod:`planner.search.progression`) is guided by the goal and
the least work left, at the price of keeping every open node.

So the depth-first search runs first, with :data:`DEPTH_FIRST_SHARE` of the
budget (and the whole node budget).  In a problem with no ``:goal``, a branch it
cuts, :data:`planner.search.depthfirst.MAX_DEPTH` decompositions deep, ends it: the tasks
alone say when the work is done, and a recursion that deep is a walk that has not
found its way (Freecell's ``ACHIEVE-CLEAR2``, which moves a card anywhere and tries
again: within 0.2-2.1 s in 50 of its 60 problems; no other domain of the IPC 2020
track with no ``:goal`` cuts a branch, in 10 s).  When it ends without a plan before
proving there is none, the best-first search gets what is left of the time: first, when
the problem grounds (:func:`planner.search.progression.relaxed_model`), guided by the
relaxed-composition heuristic (:mod:`planner.heuristics.relaxed`) for :data:`RELAXED_SHARE`
of what is left, then by the goals and the least work for the rest, restarted
with its ties broken in other orders when its first run finds nothing
(:mod:`planner.search.restarts`); for a problem with no ``:goal`` that does not ground, that
search runs :data:`PROBE_NODES` nodes as it is, then, for the rest of the time and with
the restarts, with the sizes of relaxed plans to the facts its task stacks need added to
the least work (:mod:`planner.heuristics.subgoals`).  The relaxed
heuristic sees through the hierarchy what the least work cannot
(AssemblyHierarchical's connections), but each state it meets costs an
exploration of the ground model: where that model is large (Towers,
Factories-simple) it expands ten to a hundred times fewer nodes, so the cheaper
guidance keeps its turn.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from planner.heuristics.subgoals import Subgoals
from planner.model.domain import Problem
from planner.model.plan import Plan
from planner.search import depthfirst, progression, restarts
from planner.search.branchbound import Result, Search

DEPTH_FIRST_SHARE = 1 / 3
"""The part of the time budget the depth-first search has before the best-first one
takes over (10 s of the IPC track's 30 s)."""
RELAXED_SHARE = 2 / 3
"""The part of what the depth-first search left that the best-first search guided by
the relaxed heuristic has (about 13 s of the IPC track's 30 s: AssemblyHierarchical's
deepest problem, 30 adapters, needs 5 s with the grounding on a quiet machine, twice
that on a loaded one).  The least work's turn after it (7 s) is for the problems whose
model grounds but is too large to explore at each state; the larger problems of
Multiarm-Blocksworld, which its least work solves, do not ground and have it at once."""

PROBE_NODES = 20_000
"""The nodes of the least work's search, in file order, before the subgoal estimate guides
the rest (:mod:`planner.heuristics.subgoals`): the problems with no ``:goal`` it plans, it plans
soon (Transport's pfile31, 38, 39 and 40 within 1,274 to 15,328 nodes), and the subgoal
estimate, which costs a grounding and a third of each node's time, loses them."""
PROBE_SHARE = 1 / 4
"""The most of what is left of the time that those nodes may take."""


def first_plan(problem: Problem, budget_ms: float | None = None,
               on_improvement: Callable[[Plan], None] | None = None, *,
               max_nodes: int = depthfirst.MAX_NODES) -> Result:
    """The first plan of the depth-first search within its share of ``budget_ms``
    (default: the problem's), else of the best-first searches within the rest."""
    budget = problem.budget_ms if budget_ms is None else budget_ms
    start = time.perf_counter()

    def left() -> float:
        return budget - (time.perf_counter() - start) * 1000

    goalless = not problem.goals and problem.lifted is not None  # HDDL, its tasks its aim
    first = depthfirst.first_plan(problem, budget * DEPTH_FIRST_SHARE, on_improvement,
                                  max_nodes=max_nodes, hand_over=goalless)
    if first.plan is not None or first.complete:
        return first
    stages = [first]
    relaxed, reached = None, []
    if left() > 0:
        relaxed = progression.relaxed_model(problem, reached)
        if relaxed is not None and left() > 0:
            stages.append(progression.best_first(problem, left() * RELAXED_SHARE,
                                                 max_nodes=max_nodes, relaxed=relaxed))
    subgoals = None
    if relaxed is None and goalless and not stages[-1].complete and left() > 0:
        stages.append(progression.best_first(problem, left() * PROBE_SHARE,
                                             max_nodes=min(PROBE_NODES, max_nodes)))
        if stages[-1].plan is None and not stages[-1].complete and left() > 0:
            subgoals = Subgoals.build(problem, reached[0] if reached else None)
    if stages[-1].plan is None and not stages[-1].complete and left() > 0:
        stages.append(restarts.best_first(problem, left(), max_nodes=max_nodes,
                                          subgoals=subgoals))
    last = stages[-1]
    if len(stages) == 1:
        return first
    if last.plan is not None and on_improvement is not None:
        on_improvement(last.plan)
    found = last.plan is not None
    before = sum(stage.elapsed_ms for stage in stages[:-1])
    return Result(last.plan, last.plans_found, sum(stage.expansions for stage in stages),
                  last.complete, (time.perf_counter() - start) * 1000,
                  [] if found else [f for stage in stages for f in stage.failures],
                  [(before + t, score) for t, score in last.improvements],
                  first=found)


def plan(problem: Problem, budget_ms: float | None = None,
         on_improvement: Callable[[Plan], None] | None = None, *, first: bool = False,
         max_depth: int | None = None, max_nodes: int | None = None) -> Result:
    """Plan ``problem`` within ``budget_ms`` (default: the problem's own budget), the
    depth budget ``max_depth`` and the node budget ``max_nodes`` (defaults:
    :data:`~planner.search.branchbound.MAX_DEPTH`,
    :data:`~planner.search.branchbound.MAX_NODES`); with ``first``, stop at the first
    plan."""
    budget = problem.budget_ms if budget_ms is None else budget_ms
    if problem.domain.predicates:  # HDDL: the IPC mode's searches
        if first:
            return first_plan(problem, budget, on_improvement,
                              max_nodes=max_nodes or depthfirst.MAX_NODES)
        return depthfirst.improve(problem, budget, on_improvement)
    return Search(problem, on_improvement, max_depth=max_depth,
                  max_nodes=max_nodes).run(budget, first)

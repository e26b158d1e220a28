"""The IPC mode's two searches, one after the other within one time budget.

Depth-first decomposition (:mod:`planner.depthfirst`) is what most of the IPC
2020 total-order domains need: their hierarchy says what to do, and following
it in file order finds a plan of tens of thousands of actions in seconds (Towers,
Logistics, Elevator).  Where the hierarchy leaves the work to choices that only
the goal can tell apart (Multiarm-Blocksworld, Freecell), it wanders; the
greedy best-first search (:mod:`planner.progression`) is guided by the goal and
the least work left, at the price of keeping every open node.

So the depth-first search runs first, with :data:`DEPTH_FIRST_SHARE` of the
budget (and the whole node budget); when it ends without a plan before proving
there is none, the best-first search gets what is left of the time, restarted
with its ties broken in other orders when its first run finds nothing
(:mod:`planner.restarts`).
"""

from __future__ import annotations

import time
from collections.abc import Callable

from planner import depthfirst, restarts
from planner.domain import Problem
from planner.plan import Plan
from planner.search import Result

DEPTH_FIRST_SHARE = 1 / 3
"""The part of the time budget the depth-first search has before the best-first one
takes over (10 s of the IPC track's 30 s)."""


def first_plan(problem: Problem, budget_ms: float | None = None,
               on_improvement: Callable[[Plan], None] | None = None, *,
               max_nodes: int = depthfirst.MAX_NODES) -> Result:
    """The first plan of the depth-first search within its share of ``budget_ms``
    (default: the problem's), else of the best-first search within the rest."""
    budget = problem.budget_ms if budget_ms is None else budget_ms
    start = time.perf_counter()
    first = depthfirst.first_plan(problem, budget * DEPTH_FIRST_SHARE, on_improvement,
                                  max_nodes=max_nodes)
    if first.plan is not None or first.complete:
        return first
    left = budget - (time.perf_counter() - start) * 1000
    if left <= 0:
        return first
    second = restarts.best_first(problem, left, max_nodes=max_nodes)
    if second.plan is not None and on_improvement is not None:
        on_improvement(second.plan)
    elapsed = (time.perf_counter() - start) * 1000
    found = second.plan is not None
    return Result(second.plan, second.plans_found, first.expansions + second.expansions,
                  second.complete, elapsed,
                  [] if found else [*first.failures, *second.failures],
                  [(first.elapsed_ms + t, score) for t, score in second.improvements],
                  first=found)

"""Restarts of the best-first search, each trying equally good successors in another order.

The greedy best-first search (:mod:`planner.search.progression`) breaks the ties of its
estimate by order: the successors of a choice point come in file order (methods,
then the bindings their binders propose), and the last one made is expanded first.
Where the estimate is flat -- a problem with no ``:goal`` leaves it only the task
stack's least work, as in Freecell's learned hierarchy, whose methods all look as
cheap -- that order *is* the search, and a wrong choice near the top of a long
plateau is undone only after everything below it was tried.  Such searches are
heavy-tailed (Gomes, Selman and Kautz, 1998: the same search either ends fast or
runs very long, depending on early choices), and the remedy is the one SAT and CSP
solvers use: restart, with the ties broken another way.

So the search runs first as it is, in file order (the domains it solves keep their
plans and their times), for :data:`FIRST_SHARE` of the budget (:data:`GUIDED_SHARE`
with the subgoal estimate); then, while time is
left, again and again from the start, each run shuffling each batch of successors
with its own seed (1, 2, 3...: the runs, and so the plans, are the same from one
call to the next) and each given :data:`RESTART_NODES` search nodes, or twice the
nodes of the run before once :data:`DOUBLE_AFTER` runs are done, so that a problem that needs a long
search still gets one.  A run that ends with its open list empty has proved there
is no plan (the prunings are the same whatever the order): the search stops there.

Measured on Freecell (docs/benchmarks.md): the file-order search plans 7 of the 60
problems in 30 s; with restarts, see there.
"""

from __future__ import annotations

import random
import time

from planner.heuristics.subgoals import Subgoals
from planner.model.domain import Problem
from planner.search import progression
from planner.search.branchbound import Result
from planner.search.depthfirst import MAX_NODES
from planner.search.progression import BestFirst

FIRST_SHARE = 1 / 2
"""The part of the budgets (time and nodes) the first run, in file order, has."""
GUIDED_SHARE = 2 / 3
"""That part when the subgoal estimate guides the runs (:mod:`planner.heuristics.subgoals`): it
tells the nodes apart, and its first run plans late in its time what it plans
(Freecell's 07-4: about 15 s of the 26 left), but goes astray early on some that a
shuffled run plans in 5 s (06-4)."""
RESTART_NODES = 50_000
"""The search nodes of each shuffled run: counted in nodes, not time, so that the runs,
and the plan found, do not depend on the machine's load."""
DOUBLE_AFTER = 8
"""After how many shuffled runs each run has twice the nodes of the one before."""


def best_first(problem: Problem, budget_ms: float | None = None, *,
               max_nodes: int = MAX_NODES, subgoals: Subgoals | None = None) -> Result:
    """The first plan of the best-first search of ``problem`` with restarts (see the
    module), within ``budget_ms`` (default: the problem's) and ``max_nodes`` in all;
    ``subgoals``: the estimate that guides every run with the least work."""
    budget = problem.budget_ms if budget_ms is None else budget_ms
    start = time.perf_counter()
    share = FIRST_SHARE if subgoals is None else GUIDED_SHARE
    result = progression.best_first(problem, budget * share,
                                    max_nodes=int(max_nodes * share), subgoals=subgoals)
    expansions = result.expansions
    seed, nodes = 0, RESTART_NODES
    while result.plan is None and not result.complete:
        left = budget - (time.perf_counter() - start) * 1000
        if left <= 0 or expansions >= max_nodes:
            break
        seed += 1
        if seed > DOUBLE_AFTER:
            nodes *= 2
        result = BestFirst(problem, rng=random.Random(seed), subgoals=subgoals).run(
            left, min(nodes, max_nodes - expansions))
        expansions += result.expansions
    elapsed = (time.perf_counter() - start) * 1000
    return Result(result.plan, result.plans_found, expansions, result.complete, elapsed,
                  result.failures, [(elapsed, score) for _, score in result.improvements],
                  first=result.first)

"""Greedy best-first progression search over (state, task stack): the goal-guided IPC mode.

Depth-first decomposition (:mod:`planner.search.depthfirst`) takes the first method and
binding that applies and backtracks chronologically: it has no idea how far a
choice leads from the problem's goal, so a domain whose hierarchy leaves most of
the work to choice -- Multiarm-Blocksworld's ``achieve-goals`` that may unstack
any clear block, AssemblyHierarchical's ``ConnectDevices`` that may connect any
two ports -- sends it down branches that never reach the goal, and a wrong
choice made early is undone only after everything below it was tried.

This search is the progression search of the IPC's total-order planners (PANDA's
progression, HyperTensioN's and Lilotane's front-to-back decomposition) made
*best first*: a search node is a state and the task stack left (the same nodes,
the same successors and the same prunings as the depth-first search: seen
nodes, repeated decomposition in one state, goal protection, the binders), and
the open node expanded next is the one whose estimate of the work left is
smallest:

* **goals unmet**: the problem's state goals (``:goal``) that are false in the
  node's state, each weighing :data:`GOAL_WEIGHT`;
* **the task stack's least work** (the task decomposition graph, TDG): each
  action counts 1, each compound task the least, over its methods, of its
  subtasks' counts (a fixpoint over task names, computed once), so that a method
  that leaves less to do is preferred, and a stack that cannot be finished
  (a task with no finite decomposition) is infinite.

A node with a false goal fact that no task left may add (:mod:`planner.heuristics.reach`), or
that no action below the task stack can add from the node's state, relaxed
(:mod:`planner.heuristics.support`), is dropped: it is a dead end.

Ties go to the node made last (the search stays depth first between equally good
nodes, as the plain search would).  A node's successors are drawn from its
choice point :data:`BATCH` at a time: a task with millions of bindings (the
variables of an initial task network) does not stall the search, the rest of the
bindings wait in the open list at the parent's estimate.

The plan found is evaluated as the depth-first search's is
(:class:`planner.evaluation.evaluate.Evaluator`), so the validator and the IPC writer work on
it unchanged.
"""

from __future__ import annotations

import gc
import heapq
import itertools
import math
import random
import time
from collections.abc import Iterator
from typing import Any

from planner.evaluation.evaluate import Evaluator
from planner.heuristics import grounding
from planner.heuristics.reach import GoalReach
from planner.heuristics.relaxed import Relaxed
from planner.heuristics.subgoals import Subgoals
from planner.heuristics.support import Support
from planner.model.domain import Problem
from planner.model.plan import fact_text
from planner.search import depthfirst
from planner.search.branchbound import Result
from planner.search.depthfirst import MAX_NODES, DepthFirst
from planner.search.late import Unbound, has_unbound, resolve, search_patterns, substitute

GOAL_WEIGHT = 10
"""How much one unmet goal fact weighs against one action of the task stack's least work:
the goal first, the least work between nodes equally far from it (Multiarm-Blocksworld
pfile_02_100, 100 blocks: 153,000 nodes to a plan with 10, none in 204,000 with 2)."""
BATCH = 64
"""Successors drawn from a choice point at each of its turns."""
BOUND_NODES = 5_000
"""The nodes of the first search with every method variable bound at once, when late
binding would leave some unbound (:func:`best_first`)."""
BOUND_SHARE = 1 / 4
"""The most of the time budget that first search has: where the goal facts' support
(:mod:`planner.heuristics.support`) makes each node dearer (Woodworking from 7 parts: 5,000 nodes
in 4.5 s), the late binders, which plan those problems in hundreds of nodes, keep the
rest."""
CHECK_EVERY = 32
"""Expansions between two looks at the clock."""


def least_work(problem: Problem) -> dict[str, float]:
    """For each task name, the fewest actions any decomposition of it can end in (the
    task decomposition graph's fixpoint; ``inf`` for a task no decomposition ends)."""
    domain = problem.domain
    work: dict[str, float] = {name: 1.0 for name in domain.actions}
    work.update({name: math.inf for name in domain.methods})
    changed = True
    while changed:
        changed = False
        for name, method in domain.methods.items():
            best = min((sum(work.get(sub.task, math.inf) for sub in dec.subtasks)
                        for dec in method.decompositions), default=math.inf)
            if best < work[name]:
                work[name] = best
                changed = True
    return work


def best_first(problem: Problem, budget_ms: float | None = None, *,
               max_nodes: int = MAX_NODES, relaxed: Relaxed | None = None,
               subgoals: Subgoals | None = None) -> Result:
    """The first plan of a greedy best-first search of ``problem`` (HDDL: its methods
    have binders), within ``budget_ms`` (default: the problem's) and ``max_nodes``,
    guided by ``relaxed`` (:func:`relaxed_model`) when given, else by the goals unmet
    and the task stack's least work.

    Without ``relaxed``, when some method has variables the late binders may leave
    unbound, a first search of :data:`BOUND_NODES` nodes binds them at once (the way
    the facts' index or name order proposes values sometimes finds a plan that late
    binding misses), within :data:`BOUND_SHARE` of the time, then the search with late
    binding gets the rest of the budgets.  With
    ``relaxed``, its ground model binds the tasks it holds, and method variables are
    bound at once.  ``subgoals`` (:mod:`planner.heuristics.subgoals`) adds to the least work what
    the facts the stack needs cost from the node's state; the search then binds late
    from the start (Freecell's 05-1: 8,661 nodes, where a first search of 5,000 nodes
    binding at once found nothing)."""
    budget = problem.budget_ms if budget_ms is None else budget_ms
    if relaxed is not None:
        return BestFirst(problem, relaxed, defer=False).run(budget, max_nodes)
    if subgoals is not None or not any(dec.late is not None and dec.late.may_defer
                                       for method in problem.domain.methods.values()
                                       for dec in method.decompositions):
        return BestFirst(problem, subgoals=subgoals).run(budget, max_nodes)
    start = time.perf_counter()
    first = BestFirst(problem, defer=False).run(budget * BOUND_SHARE,
                                                min(BOUND_NODES, max_nodes))
    if first.plan is not None or first.complete:
        return first
    left = budget - (time.perf_counter() - start) * 1000
    second = BestFirst(problem).run(max(left, 0.0), max(max_nodes - first.expansions, 1))
    second.expansions += first.expansions
    second.elapsed_ms = (time.perf_counter() - start) * 1000
    return second


def relaxed_model(problem: Problem, reached: list[grounding.Reached] | None = None
                  ) -> Relaxed | None:
    """The relaxed-composition heuristic of an HDDL problem (:mod:`planner.heuristics.relaxed`), or
    None when the problem does not ground within :mod:`planner.heuristics.grounding`'s limits
    (``reached``: see :func:`planner.heuristics.grounding.ground`)."""
    model = None if problem.lifted is None else grounding.ground(*problem.lifted, reached)
    return None if model is None else Relaxed(model, problem.goals)


class _Stop(Exception):
    """The node or time budget ran out."""


class BestFirst:
    """One best-first search for one problem (see the module's docstring)."""

    def __init__(self, problem: Problem, relaxed: Relaxed | None = None,
                 defer: bool = True, rng: random.Random | None = None,
                 subgoals: Subgoals | None = None):
        self.problem = problem
        self.subgoals = subgoals
        """When given (and not ``relaxed``), what the facts each node's stack needs cost
        from its state is added to the least work (:mod:`planner.heuristics.subgoals`)."""
        self.rng = rng
        """When given, each batch of successors drawn from a choice point is shuffled
        before it goes on the open list (:mod:`planner.search.restarts`), so that successors
        equally good for the estimate are tried in another order than the file's."""
        self.steps = DepthFirst(problem)
        self.steps.defer = defer
        """The depth-first search's successor generation (actions, decompositions, their
        prunings and the record of failures), shared so that both searches make the same
        nodes."""
        self.steps.max_depth = depthfirst.DEEPEST
        """Not deepened pass after pass, as the depth-first search is: as deep as it goes
        at once (the branches a depth-first search that handed over cut, :mod:`planner.
        portfolio`, are this search's to follow)."""
        self.goals = tuple((pred, args, value) for (pred, args), value in problem.goals.items())
        self.work = least_work(problem)
        self.relaxed = relaxed
        """The relaxed-composition heuristic (:mod:`planner.heuristics.relaxed`), when given: it
        replaces the goals unmet and the least work, and its ground model's bindings
        decompose the tasks it holds."""
        if relaxed is not None:
            self.steps.ground = relaxed.bindings
        self.stack_work: dict[int, float] = {}
        """The least work of each task stack met, by its hash (stacks share their tails)."""
        self.unmet: dict[int, tuple[int, frozenset[int]]] = {}
        """The number of goal facts unmet in each state met, by its hash, and which of the
        positive ones are false (their indexes in ``positive``)."""
        self.positive = [(pred, args) for pred, args, value in self.goals if value is True]
        positive = iter(range(len(self.positive)))
        self.checked = [(pred, args, value, next(positive) if value is True else -1)
                        for pred, args, value in self.goals]
        """The goal facts, each with its index in ``positive`` (-1: a negated one)."""
        self.reach = GoalReach(problem.domain, self.positive)
        self.support = (None if problem.lifted is None or not self.positive
                        else Support.of(*problem.lifted, self.positive))
        """The relaxed support of the goal facts false (:mod:`planner.heuristics.support`): a node
        with one that no action below its stack can add from its state is dropped."""
        self.expansions = 0

    def _stack(self, agenda: Any) -> float:
        """The least work of a task stack: the sum over its tasks, memoised by tail."""
        known = self.stack_work
        pending = []
        while agenda is not None and agenda[3] not in known:
            pending.append(agenda)
            agenda = agenda[4]
        total = 0.0 if agenda is None else known[agenda[3]]
        work = self.work
        for entry in reversed(pending):
            total += work.get(entry[0], math.inf)
            known[entry[3]] = total
        return total

    def _estimate(self, node: tuple) -> float:
        state, state_hash, agenda, _ = node
        if self.relaxed is not None:
            plan, unmet = self.relaxed.estimate(state, state_hash, agenda)
            return GOAL_WEIGHT * unmet + plan
        known = self.unmet.get(state_hash)
        if known is None:  # once per state: a decomposition's successors share theirs
            get = state.get
            unmet, false = 0, []
            for pred, args, value, positive in self.checked:
                if get(pred, args) != value:
                    unmet += 1
                    if positive >= 0:
                        false.append(positive)
            known = self.unmet[state_hash] = (unmet, frozenset(false))
        unmet, false = known
        if false:
            lost = false - self.reach.addable(agenda)
            if lost:  # goal facts false that no task left may add: a dead end
                if not self.steps.missed:
                    self.steps.missed = ", ".join(
                        f"{fact_text(*self.positive[i])} == True" for i in sorted(lost))
                return math.inf
            if self.support is not None and self.support.useful:
                index = self.support.unsupported(false, state, agenda)
                if index is not None:
                    if not self.steps.missed:
                        self.steps.missed = f"{fact_text(*self.positive[index])} == True"
                    return math.inf
        if self.subgoals is not None:
            return (GOAL_WEIGHT * unmet + self._stack(agenda)
                    + self.subgoals.estimate(state, state_hash, agenda))
        return GOAL_WEIGHT * unmet + self._stack(agenda)

    def run(self, budget_ms: float, max_nodes: int) -> Result:
        start = time.perf_counter()
        collecting = gc.isenabled()
        gc.disable()  # millions of acyclic tuples: see planner.search.branchbound.PAUSE_GC
        stopped = ""
        trail, roots = None, []
        try:
            trail, roots = self._search(start + budget_ms / 1000.0, max_nodes)
        except _Stop as stop:
            stopped = str(stop)
        finally:
            if collecting:
                gc.enable()
        plan = None if trail is None else Evaluator(self.problem).plan(trail, roots)
        self.steps.expansions = self.expansions
        return self.steps._outcome(plan, stopped, (time.perf_counter() - start) * 1000,
                                   budget_ms, max_nodes)

    def _search(self, deadline: float, max_nodes: int) -> tuple[Any, list[int]]:
        """The trail of the first plan (or None) and the ids of the top tasks."""
        steps = self.steps
        roots, first = steps._start(search_patterns(steps.domain, self.problem.tasks))
        node: tuple | None = first
        seen: set[int] = set()
        order = itertools.count(0, -1)  # ties: the node made last first
        open_list: list[tuple[float, int, Any]] = []
        actions, methods = steps.domain.actions, steps.domain.methods
        estimate = self._estimate
        goals = self.goals
        while True:
            if node is None:
                if not open_list:
                    return None, roots
                h, _, entry = heapq.heappop(open_list)
                if isinstance(entry, tuple):
                    node = entry
                else:  # a choice point: its next successors
                    self._tick(deadline, max_nodes)
                    self._draw(entry, h, open_list, order, seen)
                    continue
            self._tick(deadline, max_nodes)
            state, state_hash, agenda, trail = node
            node = None
            if agenda is None:
                missed = [f"{fact_text(p, a)} == {v!r}" for p, a, v in goals
                          if state.get(p, a) != v]
                if not missed:
                    return self._settle(trail), roots
                steps.missed = steps.missed or ", ".join(missed)
                continue
            name, args, parent, agenda_hash, rest = agenda
            action = actions.get(name)
            if action is not None and not has_unbound(args):  # one successor at most
                node = steps._apply(action, args, parent, state, state_hash, rest, trail)
                continue
            key = hash((state_hash, agenda_hash))
            if key in seen:
                continue
            seen.add(key)
            if action is not None:  # its arguments hold placeholders: bind them first
                choices = self._bind_action(agenda, state, state_hash, trail)
            else:
                choices = steps._decompose(methods[name], args, parent, state, state_hash,
                                           rest, trail, late=True)
            self._draw(choices, estimate((state, state_hash, agenda, trail)), open_list,
                       order, seen)

    def _bind_action(self, agenda: Any, state: Any, state_hash: int, trail: Any
                     ) -> Iterator[tuple]:
        """The front action, whose arguments hold placeholders, with each binding of them
        its precondition allows (:mod:`planner.search.late`), applied."""
        name, args, parent, _, rest = agenda
        action = self.steps.domain.actions[name]
        env = dict(zip(action.names, args, strict=True))
        for binding, subst in action.late(env, state):
            node = self.steps._apply(action, tuple([binding[p] for p in action.names]),
                                     parent, state, state_hash, substitute(rest, subst),
                                     (("bind", subst), trail))
            if node is not None:
                yield node

    def _settle(self, trail: Any) -> Any:
        """The trail of a plan with every placeholder in its records replaced by its value
        (the ``bind`` records' substitutions; a placeholder never bound: the first object
        it may be, since no condition reads it), the ``bind`` records left out."""
        records = []
        while trail is not None:
            records.append(trail[0])
            trail = trail[1]
        records.reverse()
        subst: dict[str, Any] = {}
        for record in records:
            if record[0] == "bind":
                subst.update(record[1])

        def value(v: Any) -> Any:
            v = resolve(v, subst)
            return v.objects[0] if v.__class__ is Unbound else v

        out = None
        for record in records:
            if record[0] == "bind":
                continue
            if record[0] == "method":
                binding = record[6]
                record = (*record[:4], tuple([value(a) for a in record[4]]), record[5],
                          binding if binding is None else
                          {var: value(v) for var, v in binding.items()})
            out = (record, out)
        return out

    def _tick(self, deadline: float, max_nodes: int) -> None:
        """Count one expansion; stop when a budget ran out."""
        self.expansions += 1
        if self.expansions >= max_nodes:
            raise _Stop("nodes")
        if self.expansions % CHECK_EVERY == 0 and time.perf_counter() > deadline:
            raise _Stop("time")

    def _draw(self, choices: Iterator[tuple], h: float, open_list: list, order: Any,
              seen: set[int]) -> None:
        """Put up to :data:`BATCH` successors of a choice point on the open list, and the
        choice point itself again (at its parent's estimate) if it has more."""
        estimate = self._estimate
        batch = list(itertools.islice(choices, BATCH))
        if self.rng is not None:
            self.rng.shuffle(batch)
        for child in batch:
            agenda = child[2]
            if agenda is not None and hash((child[1], agenda[3])) in seen:
                continue
            value = estimate(child)
            if value < math.inf:
                heapq.heappush(open_list, (value, next(order), child))
        if len(batch) == BATCH:  # the choice point may have more
            heapq.heappush(open_list, (h, next(order), choices))

"""Greedy best-first progression search over (state, task stack): the goal-guided IPC mode.

Depth-first decomposition (:mod:`planner.depthfirst`) takes the first method and
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

Ties go to the node made last (the search stays depth first between equally good
nodes, as the plain search would).  A node's successors are drawn from its
choice point :data:`BATCH` at a time: a task with millions of bindings (the
variables of an initial task network) does not stall the search, the rest of the
bindings wait in the open list at the parent's estimate.

The plan found is evaluated as the depth-first search's is
(:class:`planner.evaluate.Evaluator`), so the validator and the IPC writer work on
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

from planner import grounding
from planner.depthfirst import MAX_NODES, DepthFirst
from planner.domain import Problem
from planner.evaluate import Evaluator
from planner.plan import fact_text
from planner.relaxed import Relaxed
from planner.search import Result
from planner.translate import NETWORK

GOAL_WEIGHT = 10
"""How much one unmet goal fact weighs against one action of the task stack's least work:
the goal first, the least work between nodes equally far from it (Multiarm-Blocksworld
pfile_02_100, 100 blocks: 153,000 nodes to a plan with 10, none in 204,000 with 2)."""
BATCH = 64
"""Successors drawn from a choice point at each of its turns."""
CHECK_EVERY = 32
"""Expansions between two looks at the clock."""


class Unbound:
    """A parameter of the initial task network not bound yet (:meth:`BestFirst._bind`):
    it equals any value, so that goal protection (``Domain.may_add``) counts a task
    that names it as one that may add any fact of its kind."""

    __slots__ = ("name",)

    def __init__(self, name: str):
        self.name = name

    def __eq__(self, other: object) -> bool:
        return True

    def __ne__(self, other: object) -> bool:
        return False

    def __hash__(self) -> int:
        return hash(("?", self.name))

    def __str__(self) -> str:
        return self.name


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
               max_nodes: int = MAX_NODES, relaxed: Relaxed | None = None) -> Result:
    """The first plan of a greedy best-first search of ``problem`` (HDDL: its methods
    have binders), within ``budget_ms`` (default: the problem's) and ``max_nodes``,
    guided by ``relaxed`` (:func:`relaxed_model`) when given, else by the goals unmet
    and the task stack's least work."""
    budget = problem.budget_ms if budget_ms is None else budget_ms
    return BestFirst(problem, relaxed).run(budget, max_nodes)


def relaxed_model(problem: Problem) -> Relaxed | None:
    """The relaxed-composition heuristic of an HDDL problem (:mod:`planner.relaxed`), or
    None when the problem does not ground within :mod:`planner.grounding`'s limits."""
    model = None if problem.lifted is None else grounding.ground(*problem.lifted)
    return None if model is None else Relaxed(model, problem.goals)


class _Stop(Exception):
    """The node or time budget ran out."""


class BestFirst:
    """One best-first search for one problem (see the module's docstring)."""

    def __init__(self, problem: Problem, relaxed: Relaxed | None = None,
                 rng: random.Random | None = None):
        self.problem = problem
        self.rng = rng
        """When given, each batch of successors drawn from a choice point is shuffled
        before it goes on the open list (:mod:`planner.restarts`), so that successors
        equally good for the estimate are tried in another order than the file's."""
        self.steps = DepthFirst(problem)
        """The depth-first search's successor generation (actions, decompositions, their
        prunings and the record of failures), shared so that both searches make the same
        nodes."""
        self.goals = tuple((pred, args, value) for (pred, args), value in problem.goals.items())
        self.work = least_work(problem)
        self.relaxed = relaxed
        """The relaxed-composition heuristic (:mod:`planner.relaxed`), when given: it
        replaces the goals unmet and the least work, and its ground model's bindings
        decompose the tasks it holds."""
        if relaxed is not None:
            self.steps.ground = relaxed.bindings
        self.stack_work: dict[int, float] = {}
        """The least work of each task stack met, by its hash (stacks share their tails)."""
        self.unmet: dict[int, int] = {}
        """The number of goal facts unmet in each state met, by its hash."""
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
        unmet = self.unmet.get(state_hash)
        if unmet is None:  # once per state: a decomposition's successors share theirs
            get = state.get
            unmet = sum(1 for pred, args, value in self.goals if get(pred, args) != value)
            self.unmet[state_hash] = unmet
        return GOAL_WEIGHT * unmet + self._stack(agenda)

    def run(self, budget_ms: float, max_nodes: int) -> Result:
        start = time.perf_counter()
        collecting = gc.isenabled()
        gc.disable()  # millions of acyclic tuples: see planner.search.PAUSE_GC
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
        roots, first = steps._start()
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
                    settled = self._settle(trail, state)
                    if settled is not None:
                        return settled, roots
                steps.missed = steps.missed or ", ".join(missed)
                continue
            name, args, parent, agenda_hash, rest = agenda
            action = actions.get(name)
            if action is not None:  # one successor at most: follow it at once
                node = steps._apply(action, args, parent, state, state_hash, rest, trail)
                continue
            key = hash((state_hash, agenda_hash))
            if key in seen:
                continue
            seen.add(key)
            if name == NETWORK:
                choices = self._open_network(parent, state, state_hash, rest, trail)
            elif any(a.__class__ is Unbound for a in args):
                choices = self._bind(agenda, state, state_hash, trail)
            else:
                choices = steps._decompose(methods[name], args, parent, state, state_hash,
                                           rest, trail)
            self._draw(choices, estimate((state, state_hash, agenda, trail)), open_list,
                       order, seen)

    # -- the initial task network's parameters, bound late -----------------------------

    def _open_network(self, parent: Any, state: Any, state_hash: int, rest: Any,
                      trail: Any) -> Iterator[tuple]:
        """The network's tasks, their parameters left :class:`Unbound`: each is bound when
        the first task that names it comes to the front (:meth:`_bind`), to the objects of
        its type, so that a wrong value is found out by that task alone -- not by the
        whole network's every combination of values, as binding them all at once would."""
        steps = self.steps
        dec = steps.domain.methods[NETWORK].decompositions[0]
        local = {var: Unbound(var) for var, _ in dec.vars}
        node = (parent, (NETWORK, ()), parent[2], state_hash, next(steps.ids), parent[5] + 1)
        agenda = rest
        for sub in reversed(dec.subtasks):
            values = sub.values(local) if sub.values is not None else tuple(
                [a.fn(local, state.get) for a in sub.args])
            agenda = (sub.task, values, node,
                      hash((sub.task, values, agenda[3] if agenda else 0)), agenda)
        record = ("method", node[4], parent[4], NETWORK, (), dec.name, None)
        yield state, state_hash, agenda, (record, trail)

    def _bind(self, agenda: Any, state: Any, state_hash: int, trail: Any
              ) -> Iterator[tuple]:
        """The front task's unbound parameters bound to every combination of the objects
        of their types, through the whole task stack (only the network's tasks are left
        on it: they are the bottom of the stack)."""
        dec = self.steps.domain.methods[NETWORK].decompositions[0]
        kinds = dict(dec.vars)
        free = list(dict.fromkeys(a.name for a in agenda[1] if a.__class__ is Unbound))
        domain, entities = self.problem.domain, self.problem.entities
        choices = [sorted(o for o, t in entities.items() if domain.is_subtype(t, kinds[var]))
                   for var in free]
        entries = []
        entry = agenda
        while entry is not None:
            entries.append(entry)
            entry = entry[4]
        for values in itertools.product(*choices):
            chosen = dict(zip(free, values, strict=True))
            rebuilt = None
            for name, args, parent, _, _ in reversed(entries):
                args = tuple([chosen.get(a.name, a) if a.__class__ is Unbound else a
                              for a in args])
                rebuilt = (name, args, parent, hash((name, args, rebuilt[3] if rebuilt else 0)),
                           rebuilt)
            yield state, state_hash, rebuilt, (("bind", chosen), trail)

    def _settle(self, trail: Any, final: Any) -> Any:
        """The trail of a plan with the network's record given its binding (the values
        chosen by :meth:`_bind`; a parameter no task names: the first object of its type
        that meets the network's constraints), or None when the constraints are not met."""
        records = []
        while trail is not None:
            records.append(trail[0])
            trail = trail[1]
        records.reverse()
        if not any(r[0] == "bind" for r in records) and not any(
                r[0] == "method" and r[3] == NETWORK for r in records):
            out = None
            for record in records:
                out = (record, out)
            return out
        chosen: dict[str, Any] = {}
        for record in records:
            if record[0] == "bind":
                chosen.update(record[1])
        dec = self.steps.domain.methods[NETWORK].decompositions[0]
        domain, entities = self.problem.domain, self.problem.entities
        initial = self.problem.initial.get
        free = [(var, kind) for var, kind in dec.vars if var not in chosen]
        options = [sorted(o for o, t in entities.items() if domain.is_subtype(t, kind))
                   for _, kind in free]
        for values in itertools.product(*options):
            env = {**chosen, **{var: v for (var, _), v in zip(free, values, strict=True)}}
            if dec.pre is None or dec.pre.fn(env, initial):
                break
        else:
            return None
        out = None
        for record in records:
            if record[0] == "bind":
                continue
            if record[0] == "method" and record[3] == NETWORK:
                record = (*record[:6], {var: env[var] for var, _ in dec.vars})
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

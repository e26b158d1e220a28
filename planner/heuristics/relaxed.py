"""A relaxed-composition heuristic for the best-first search: how much a task stack still
needs, seen through the ground hierarchy and the state.

The best-first search's own estimate (:func:`planner.search.progression.least_work`) counts
the fewest actions each task can end in, whatever the state: in
AssemblyHierarchical, connecting the right two ports and connecting two ports
that no chain uses cost the same (one ``connect``), and nothing before the final
validation tells them apart.  PANDA's RC heuristic (Höller et al., "A Generic
Method to Guide HTN Progression Search with Classical Heuristics", ICAPS 2018)
does: it relaxes the hierarchy into a classical problem where each ground
action adds its effects *and* the fact "this task was done", and each ground
method adds "its task was done" once its precondition holds and its subtasks
were done, and asks a delete-relaxed planning heuristic for the tasks of the
stack.

Here, on the model of :mod:`planner.heuristics.grounding`:

* per state (once: a decomposition's successors share it), the additive cost
  of every fact and every ground task, by a Dijkstra-like exploration of that
  AND/OR graph (actions cost 1, methods 0), with each one's cheapest supporter;
* per node, the **relaxed plan** (h_FF): the set of ground actions the
  supporters use, for every task of the stack and every goal fact unmet, so
  that an action that serves two of them counts once -- connecting two ports
  the validation chain needs is in the relaxed plan of the validation already,
  and a child whose ``connect`` is one of them gets a smaller estimate than its
  siblings, before any of them is applied.

A task of the stack whose cost is infinite (no relaxed decomposition from this
state) or that the ground model does not hold (it can be part of no plan) makes
the node a dead end.  Negative preconditions and deletions are relaxed away: a
wrong ``connect`` that occupies a port the chain needs is not seen until the
search fails below it.
"""

from __future__ import annotations

import heapq
import math
from typing import Any

from planner.heuristics.grounding import Grounded

MEMO = 50_000
"""Task-stack tails whose relaxed plans are kept (the memo is emptied beyond: a plan is
a set of up to a few hundred action ids, and the tails of one state's stacks are what
its successors share)."""
STATES = 64
"""States whose explorations are kept (emptied beyond): a node's successors share one."""


class Relaxed:
    """The relaxed-composition model of one ground problem, and its estimates."""

    def __init__(self, model: Grounded, goals: dict[tuple[str, Any], Any]):
        self.bindings = model.bindings
        """The ground model's method bindings, for the search that this heuristic guides
        (:attr:`planner.search.depthfirst.DepthFirst.ground`)."""
        facts = model.facts
        self.fact_keys = list(facts)
        n_facts = len(facts)
        self.n_nodes = n_facts + len(model.tasks)
        ops_pre: list[tuple[int, ...]] = []
        ops_eff: list[tuple[int, ...]] = []
        ops_cost: list[int] = []
        ops_action: list[int] = []
        task_of = {a: t for t, a in model.primitive.items()}
        for a, (pre, add) in enumerate(zip(model.action_pre, model.action_add, strict=True)):
            ops_pre.append(pre)
            ops_eff.append((*add, n_facts + task_of[a]))
            ops_cost.append(1)
            ops_action.append(a)
        for task, pre, subtasks in model.methods:
            ops_pre.append(tuple(dict.fromkeys((*pre, *(n_facts + s for s in subtasks)))))
            ops_eff.append((n_facts + task,))
            ops_cost.append(0)
            ops_action.append(-1)
        self.ops_pre, self.ops_eff, self.ops_cost = ops_pre, ops_eff, ops_cost
        self.ops_action = ops_action
        self.consumers: list[list[int]] = [[] for _ in range(self.n_nodes)]
        for op, pre in enumerate(ops_pre):
            for node in pre:
                self.consumers[node].append(op)
        self.free_ops = [op for op, pre in enumerate(ops_pre) if not pre]
        self.producers: dict[int, list[int]] = {}
        """The operators that make each task done (its methods, or its action)."""
        for op, effects in enumerate(ops_eff):
            self.producers.setdefault(effects[-1], []).append(op)
        self.task_node = {task: n_facts + t for task, t in model.tasks.items()}
        self.goals = [(facts.get((pred, args)), pred, args) for (pred, args), value
                      in goals.items() if value is True]
        self.negative_goals = [(pred, args) for (pred, args), value in goals.items()
                               if value is not True]
        self.states: dict[int, _Costs] = {}
        self.tails: dict[tuple[int, int], frozenset[int] | None] = {}

    def estimate(self, state: Any, state_hash: int, agenda: Any) -> tuple[float, int]:
        """The relaxed plan's size for the stack ``agenda`` and the unmet goals in
        ``state`` (``inf``: a dead end), and the number of goal facts unmet."""
        costs = self.states.get(state_hash)
        if costs is None:
            if len(self.states) >= STATES:
                self.states.clear()
            costs = self.states[state_hash] = self._explore(state)
        tails = self.tails
        if len(tails) >= MEMO:
            tails.clear()
        pending = []
        entry = agenda
        while entry is not None and (state_hash, entry[3]) not in tails:
            pending.append(entry)
            entry = entry[4]
        if entry is None:
            key = (state_hash, 0)
            found = tails.get(key, False)
            if found is False:
                found = tails[key] = costs.goal_plan
            plan = found
        else:
            plan = tails[(state_hash, entry[3])]
        task_node = self.task_node
        for entry in reversed(pending):
            if plan is not None:
                node = task_node.get((entry[0], entry[1]))
                plan = None if node is None else costs.join(plan, node)
            tails[(state_hash, entry[3])] = plan
        return (math.inf if plan is None else float(len(plan))), costs.unmet

    def _explore(self, state: Any) -> _Costs:
        """Every fact's and task's additive cost from ``state``, and its supporter."""
        get = state.get
        cost = [math.inf] * self.n_nodes
        support = [-1] * self.n_nodes
        heap: list[tuple[float, int]] = []
        for node, (pred, args) in enumerate(self.fact_keys):
            if get(pred, args) is True:
                cost[node] = 0
                heap.append((0, node))
        ops_pre, ops_eff, ops_cost = self.ops_pre, self.ops_eff, self.ops_cost
        waiting = [len(pre) for pre in ops_pre]
        total = [0.0] * len(ops_pre)
        for op in self.free_ops:
            value = ops_cost[op]
            for node in ops_eff[op]:
                if value < cost[node]:
                    cost[node], support[node] = value, op
                    heap.append((value, node))
        heapq.heapify(heap)
        consumers = self.consumers
        done = [False] * self.n_nodes
        while heap:
            value, node = heapq.heappop(heap)
            if done[node]:
                continue
            done[node] = True
            for op in consumers[node]:
                total[op] += value
                waiting[op] -= 1
                if waiting[op] == 0:
                    reached = total[op] + ops_cost[op]
                    for effect in ops_eff[op]:
                        if reached < cost[effect]:
                            cost[effect], support[effect] = reached, op
                            heapq.heappush(heap, (reached, effect))
        costs = _Costs(self, cost, support)
        unmet = 0
        plan: frozenset[int] | None = frozenset()
        for node, pred, args in self.goals:
            if get(pred, args) is True:
                continue
            unmet += 1
            mine = None if node is None else costs.plan(node)
            plan = None if plan is None or mine is None else plan | mine
        unmet += sum(1 for pred, args in self.negative_goals if get(pred, args) is not None)
        costs.unmet, costs.goal_plan = unmet, plan
        return costs


class _Costs:
    """One state's exploration: costs, supporters, and the relaxed plan of each node."""

    def __init__(self, relaxed: Relaxed, cost: list[float], support: list[int]):
        self.relaxed = relaxed
        self.cost = cost
        self.support = support
        self.plans: dict[int, frozenset[int]] = {}
        self.unmet = 0
        self.goal_plan: frozenset[int] | None = frozenset()

    def join(self, plan: frozenset[int], node: int) -> frozenset[int] | None:
        """``plan`` and the relaxed plan of the task ``node`` by whichever of its methods
        adds the fewest actions to ``plan`` (None when the task is out of reach).

        The choice is made here, in context, rather than by the cheapest supporter alone:
        AssemblyHierarchical's ``connect`` of two ports that can both face either way has
        two methods (``connect_7``, ``connect_8``) of one cost, and the validation's
        relaxed plan uses one of them; the task must count as already in it."""
        best: frozenset[int] | None = None
        for op in self.relaxed.producers.get(node, ()):
            mine = self.op_plan(op)
            if mine is None:
                continue
            joined = plan | mine if mine else plan
            if best is None or len(joined) < len(best):
                best = joined
        return best

    def op_plan(self, op: int) -> frozenset[int] | None:
        """The relaxed plan of an operator: its preconditions' and its own action."""
        relaxed = self.relaxed
        parts = []
        for pre in relaxed.ops_pre[op]:
            part = self.plan(pre)
            if part is None:
                return None
            parts.append(part)
        mine: frozenset[int] = frozenset().union(*parts) if parts else frozenset()
        action = relaxed.ops_action[op]
        return mine | {action} if action >= 0 else mine

    def plan(self, node: int) -> frozenset[int] | None:
        """The ground actions of ``node``'s relaxed plan (its supporters, down to the
        state's facts), or None when it is out of reach; iterative (chains are long)."""
        plans, cost, support = self.plans, self.cost, self.support
        if node in plans:
            return plans[node]
        if cost[node] == math.inf:
            return None
        relaxed = self.relaxed
        ops_pre = relaxed.ops_pre
        todo = [node]
        while todo:
            current = todo[-1]
            if current in plans:
                todo.pop()
                continue
            op = support[current]
            if op < 0:
                plans[current] = frozenset()
                todo.pop()
                continue
            missing = [p for p in ops_pre[op] if p not in plans]
            if missing:
                todo.extend(missing)
                continue
            todo.pop()
            plans[current] = self.op_plan(op)  # type: ignore[assignment]
        return plans[node]

"""What a task stack still needs, and what reaching it costs from a state: the estimate of
the best-first search for problems with no ``:goal`` whose methods are too many to ground.

Freecell's learned hierarchy (IPC 2020, Freecell-Learned-ECAI-16) has no ``:goal``: the
problem's aim is in its top tasks (``ACHIEVE-HOME S5``...), and each method's aim in its
subtasks (``ACHIEVE-COLSPACE ?n``, ``ACHIEVE-CLEAR ?c``).  The search's own estimate,
the task stack's least work, reads no state: ``ACHIEVE-COLSPACE N9`` (nine free columns,
a walk of the game that never ends) costs what ``ACHIEVE-COLSPACE N2`` costs where two
columns are free (nothing), so the search wandered (02-1, eight cards: a plan after
170,000 nodes, 468 states).  The relaxed-composition heuristic (:mod:`planner.heuristics.relaxed`)
would see it, but its ground model has 142,000 methods at 2 cards a suit, 421,000 at 5
(40 s to build), one Dijkstra over it per state.

This estimate keeps the hierarchy lifted and grounds only the actions:

* **What a task needs** (:func:`task_needs`, lifted, once): the facts that every way of
  doing it needs or ends with, over its parameters.  An action needs its precondition's
  facts; a method needs its precondition's facts and what each of its subtasks needs;
  a compound task needs what all its methods need (the intersection; a method that
  needs nothing of the kind -- only bookkeeping, as ``M112-ACHIEVE-HOME`` when the fact
  is locked already -- is left out of it).  A method that ends when a fact holds (the
  base case of a recursion) needs that fact, so ``ACHIEVE-HOME0 ?c`` needs ``HOME ?c``,
  ``ACHIEVE-COLSPACE ?n`` needs ``COLSPACE ?n``, and ``DO-ON-SENDTOFREE0 ?c0 ?c1 ?n2
  ?n3`` needs ``ON ?c0 ?c1``, ``CLEAR ?c0`` and ``CELLSPACE ?n2``.  Only facts some
  action changes and some action needs count (``LOCKED-*`` and ``FLAGGED-*`` appear
  in none's positive precondition; ``SUCCESSOR`` never changes).
* **What a fact costs from a state** (per state: a decomposition's successors share it):
  the size of a relaxed plan to it, as FF's (Hoffmann and Nebel, 2001), over the ground
  actions that relaxed reachability keeps (:func:`planner.heuristics.grounding.reachable_actions`:
  13,375 distinct at 7 cards a suit, about 1 s), each costing 1, deletions ignored.  The
  additive cost h_add (Bonet and Geffner, 2001) is computed first, as a fixpoint over
  arrays (numpy) whose rounds revise only the actions a fact just made cheaper reads
  (about 3 ms a state at 7 cards a suit); then, for each fact a node needs, the walk back
  from it through each false fact's cheapest adder counts the actions met, each once.
  h_add alone counts what several preconditions share once for each: a card home needs
  the cards below it home, each of those the same, so its cost grows with the square of
  the cards.  Of Freecell's 06-1, 06-4, 07-4, 07-5, 08-1 and 08-4, which h_add plans
  none of in 25 s (one search, file order), the relaxed plans plan 06-1 and 07-4 (16
  and 24 s).
* **Per node**: the sum, over the tasks of the stack, of the costs of the facts each
  needs (a fact out of relaxed reach counts :data:`UNREACHED`, not a dead end: what a
  task needs is an estimate), kept by the tail of the stack, so a node pays for the tasks
  its decomposition put on the stack only.

So the wrong ``ACHIEVE-COLSPACE N9`` costs seven moves and the right one nothing, and a
card on its way home costs less with each card cleared off it.  What it does not see:
deletions (a card sent to a free cell takes a cell the next card needs), and what a
method needs through variables its task does not have.
"""

from __future__ import annotations

from typing import Any

import numpy

from planner.heuristics import grounding
from planner.io import hddl
from planner.model.domain import Problem
from planner.model.formulas import conjuncts

UNREACHED = 1000
"""What a needed fact out of relaxed reach from the state costs."""
ACTION_LIMIT = 600_000
"""Ground actions (and bindings tried) beyond which the actions are not grounded and this
estimate is given up (Freecell with 13 cards a suit: about 30,000 actions)."""
ACTION_SECONDS = 5.0
"""Seconds of grounding beyond which this estimate is given up."""
MEMO = 200_000
"""Stack tails whose sums are kept (emptied beyond)."""
STATES = 4_096
"""States whose fact costs are kept (emptied beyond)."""

Need = tuple[str, tuple[int | str, ...]]
"""A fact a task needs: its predicate and, per argument, the task's parameter position
(an int) or a constant (a str)."""


def task_needs(domain: hddl.HDDLDomain) -> dict[str, tuple[Need, ...]]:
    """For each task name (action or compound task), the facts every way of doing it
    needs (see the module's docstring); a fixpoint over the methods."""
    changed_preds: set[str] = set()
    for action in domain.actions.values():
        for formula in ([] if action.effect is None else action.effect.walk()):
            if formula.kind == "pred":
                changed_preds.add(formula.children[0])
    relevant = {f.children[0] for action in domain.actions.values()
                for f in conjuncts(action.precondition) if f.kind == "pred"} & changed_preds
    needs: dict[str, frozenset[Need] | None] = {}
    for name, action in domain.actions.items():
        names = [p for p, _ in action.params]
        needs[name] = frozenset(
            (f.children[0], tuple(names.index(t) if t in names else t for t in f.children[1]))
            for f in conjuncts(action.precondition)
            if f.kind == "pred" and f.children[0] in relevant)
    by_task: dict[str, list[hddl.HMethod]] = {}
    for method in domain.methods:
        by_task.setdefault(method.task.name, []).append(method)
        needs.setdefault(method.task.name, None)

    def of_method(method: hddl.HMethod) -> set[Need] | None:
        head = list(method.task.args)
        out: set[Need] = set()

        def add(pred: str, terms: tuple[str, ...]) -> None:
            mapped: list[int | str] = []
            for term in terms:
                if not term.startswith("?"):
                    mapped.append(term)
                elif term in head:
                    mapped.append(head.index(term))
                else:
                    return  # a method variable: not a need of the task
            out.add((pred, tuple(mapped)))

        for f in conjuncts(method.precondition):
            if f.kind == "pred" and f.children[0] in relevant:
                add(f.children[0], tuple(f.children[1]))
        for sub in method.subtasks:
            known = needs.get(sub.name)
            if known is None:
                return None
            for pred, terms in known:
                add(pred, tuple(sub.args[t] if isinstance(t, int) else t for t in terms))
        return out

    for _ in range(64):  # converges in a few rounds; bounded all the same
        changed = False
        for task, methods in by_task.items():
            mine: set[Need] | None = None
            known = False
            for method in methods:
                found = of_method(method)
                if found is None:
                    continue
                known = True
                if found:
                    mine = found if mine is None else mine & found
            if known:
                value = frozenset(mine or ())
                if needs[task] != value:
                    needs[task] = value
                    changed = True
        if not changed:
            break
    return {task: tuple(sorted(value or (), key=repr)) for task, value in needs.items()}


class Subgoals:
    """The estimate of one problem (see the module): :meth:`estimate` for a node."""

    def __init__(self, needs: dict[str, tuple[Need, ...]],
                 actions: dict[str, list[tuple[tuple[str, ...], list[Any], list[Any]]]],
                 initial: list[tuple[str, tuple[str, ...]]]):
        self.needs = needs
        relevant = {pred for task in needs.values() for pred, _ in task}
        ids: dict[tuple[str, tuple[str, ...]], int] = {}
        for fact in initial:  # true from the start, maybe added by no action
            if fact[0] in relevant:
                ids.setdefault(fact, len(ids))
        rows: dict[tuple[tuple[int, ...], tuple[int, ...]], None] = {}
        for ground in actions.values():
            for _, pre, add in ground:
                adds = tuple(sorted({ids.setdefault(f, len(ids)) for f in add
                                     if f[0] in relevant}))
                if adds:
                    pres = tuple(sorted({ids.setdefault(f, len(ids)) for f in pre
                                         if f[0] in relevant}))
                    rows[(pres, adds)] = None  # actions alike for the estimate count once
        self.ids = ids
        self.facts = list(ids)
        n = len(ids)
        width = max((len(pre) for pre, _ in rows), default=0) or 1
        self.pre = numpy.full((len(rows), width), n, dtype=numpy.int64)
        """Each action's precondition facts, padded with ``n``: a fact that costs 0."""
        pairs = []
        for index, (pre, adds) in enumerate(rows):
            self.pre[index, :len(pre)] = pre
            pairs.extend((fact, index) for fact in adds)
        pairs.sort()
        self.adders = numpy.array([a for _, a in pairs], dtype=numpy.int64)
        """The actions adding each fact, grouped by fact (``added`` says which)."""
        added = numpy.array([f for f, _ in pairs], dtype=numpy.int64)
        self.added, self.starts = numpy.unique(added, return_index=True)
        ends = [*self.starts[1:].tolist(), len(pairs)]
        self.supporters: list[Any] = [None] * n
        """Each fact's adders (an array of action indexes; None: no action adds it)."""
        for fact, begin, end in zip(self.added.tolist(), self.starts.tolist(), ends,
                                    strict=True):
            self.supporters[fact] = self.adders[begin:end]
        self.needed: list[tuple[int, ...]] = [pre for pre, _ in rows]
        """Each action's precondition facts, unpadded: the relaxed plans' walk reads them."""
        users: list[list[int]] = [[] for _ in range(n)]
        for index, pre in enumerate(self.needed):
            for fact in pre:
                users[fact].append(index)
        self.users = [numpy.array(indexes, dtype=numpy.int64) for indexes in users]
        """The actions each fact is a precondition of: those whose cost a round revises
        when the fact's cost falls."""
        self.states: dict[int, Costs] = {}
        self.tails: dict[tuple[int, int], float] = {}
        self.size = len(rows)

    @classmethod
    def build(cls, problem: Problem, actions: grounding.Reached | None = None
              ) -> Subgoals | None:
        """The estimate of an HDDL ``problem`` (with its relaxed-reachable ``actions``,
        when they were grounded already), or None when its actions do not ground within
        :data:`ACTION_LIMIT` and :data:`ACTION_SECONDS`."""
        if problem.lifted is None:
            return None
        domain, hproblem = problem.lifted
        if actions is None:
            actions = grounding.reachable_actions(domain, hproblem, ACTION_LIMIT,
                                                  ACTION_SECONDS)
        if actions is None:
            return None
        return cls(task_needs(domain), actions, [(f.pred, f.args) for f in hproblem.init])

    def costs(self, state: Any) -> Costs:
        """What each fact costs from ``state``: its additive relaxed cost, a fixpoint (each
        round, each action costs one plus its preconditions' costs, each fact its cheapest
        adder's), and the size of its relaxed plan, drawn from it (:class:`Costs`)."""
        n = len(self.facts)
        cost = numpy.full(n + 1, float(UNREACHED * 64))
        cost[n] = 0.0
        get = state.get
        for index, (pred, args) in enumerate(self.facts):
            if get(pred, args) is True:
                cost[index] = 0.0
        reached = numpy.zeros(0)
        if self.size:
            users = self.users
            reached = cost[self.pre].sum(axis=1) + 1.0
            while True:
                cheapest = numpy.minimum.reduceat(reached[self.adders], self.starts)
                better = cheapest < cost[self.added]
                if not better.any():
                    break
                changed = self.added[better]
                cost[changed] = cheapest[better]
                touched = numpy.concatenate([users[fact] for fact in changed.tolist()])
                reached[touched] = cost[self.pre[touched]].sum(axis=1) + 1.0
        return Costs(self, numpy.minimum(cost, UNREACHED).tolist(), reached)

    def estimate(self, state: Any, state_hash: int, agenda: Any) -> float:
        """The sum, over the tasks of the stack ``agenda``, of the sizes of the relaxed
        plans from ``state`` to the facts each needs (kept by the state and the stack's
        tail)."""
        tails = self.tails
        pending = []
        entry = agenda
        while entry is not None and (state_hash, entry[3]) not in tails:
            pending.append(entry)
            entry = entry[4]
        if not pending:
            return 0.0 if agenda is None else tails[(state_hash, agenda[3])]
        total = 0.0 if entry is None else tails[(state_hash, entry[3])]
        costs = self.states.get(state_hash)
        if costs is None:
            if len(self.states) >= STATES:
                self.states.clear()
            costs = self.states[state_hash] = self.costs(state)
        if len(tails) >= MEMO:
            tails.clear()
        ids, needs, plan = self.ids, self.needs, costs.plan
        for entry in reversed(pending):
            args = entry[1]
            for pred, terms in needs.get(entry[0], ()):
                fact = (pred, tuple([args[t] if t.__class__ is int else t for t in terms]))
                index = ids.get(fact)
                if index is not None:
                    total += plan(index)
                elif all(value.__class__ is str for value in fact[1]):
                    total += UNREACHED  # else a placeholder (planner.search.late): not known yet
            tails[(state_hash, entry[3])] = total
        return total


class Costs:
    """What the facts cost from one state: ``additive`` (h_add, a list by fact index) and,
    drawn from it on demand, :meth:`plan`."""

    __slots__ = ("subgoals", "additive", "reached", "plans")

    def __init__(self, subgoals: Subgoals, additive: list[float], reached: Any):
        self.subgoals = subgoals
        self.additive = additive
        self.reached = reached
        """Each action's additive cost: its preconditions' costs plus one."""
        self.plans: dict[int, float] = {}

    def plan(self, fact: int) -> float:
        """The size of a relaxed plan for ``fact`` (as FF's, Hoffmann and Nebel, 2001):
        from the fact back, each false fact's cheapest adder, each action counted once,
        so that what several preconditions share counts once, where h_add counts it for
        each."""
        known = self.plans.get(fact)
        if known is not None:
            return known
        additive = self.additive
        if additive[fact] >= UNREACHED:
            self.plans[fact] = UNREACHED
            return UNREACHED
        supporters, needed, reached = (self.subgoals.supporters, self.subgoals.needed,
                                       self.reached)
        chosen: set[int] = set()
        seen: set[int] = set()
        todo = [fact]
        while todo:
            current = todo.pop()
            if current in seen or additive[current] == 0:
                continue
            seen.add(current)
            adders = supporters[current]
            best = int(adders[reached[adders].argmin()])
            if best not in chosen:
                chosen.add(best)
                todo.extend(needed[best])
        self.plans[fact] = size = float(len(chosen))
        return size

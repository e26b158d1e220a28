"""SHOP2-style HTN search, anytime branch and bound, iterative, deterministic.

Tasks are decomposed in order (total-order HTN, like SHOP2, which HATP's
algorithm is "largely inspired from"): the first task of the agenda is an
action (its precondition is checked and its effects applied) or a method
(each decomposition, in file order, for each binding of its variables, in
name order, whose precondition holds, replaces it by its subtasks).  Agents
are bound like any other variable, which is how a plan comes to involve the
robot and the humans.

The search is a depth-first walk over an explicit stack of choice points
(no recursion, so no depth limit), with copy-on-write states.  It is
*anytime*: every complete plan is evaluated (:mod:`planner.evaluate`); the
best so far is kept, reported to ``on_improvement``, and used to prune: a
partial plan whose lower bound (the monotone part of the score: cost and
effort so far) cannot beat it is abandoned.  When the time budget runs out,
the best plan found so far is returned.  With ``first=True`` (satisficing, as
in the IPC's HTN track) it stops at the first plan instead.

HDDL methods bind their free variables from the state's facts
(:class:`~planner.domain.Decomposition` ``bind``, :mod:`planner.binding`),
and their states index those facts (:class:`~planner.state.FactState`).
HDDL problems also have goal protection: an action that deletes a goal fact
that no task left on the agenda may add again (``Domain.adds``, a lifted
analysis of the hierarchy) ends its branch there, rather than at the goal
check after the last task -- which, in Blocksworld-GTOHP, is the difference
between backtracking one choice and backtracking over the whole plan.

Left recursion -- a task whose decomposition starts, before any action, with
the very same task (IPC feature test ``abort-iteration``) -- would send a
depth-first search down forever.  The search therefore refuses to decompose a
task again in the state where an ancestor decomposed it, more than
``repeats`` times on the path; ``repeats`` starts at 0 and, if the search
ends without a plan because of that refusal, it starts again with one more,
within the same time budget, up to :data:`MAX_REPEATS` (iterative deepening
on the repetitions: a plan that needs a few repetitions is still found; with a
plan in hand, plans that need more repetitions are not looked for).
"""

from __future__ import annotations

import gc
import itertools
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

from planner.domain import SOLE_AGENT, Action, Method, Problem
from planner.evaluate import Evaluator
from planner.plan import Plan, fact_text
from planner.state import FactState, State

CHECK_EVERY = 256
"""Expansions between two looks at the clock."""
MAX_REPEATS = 8
"""The most repetitions of a left-recursive decomposition the deepening allows."""
PAUSE_GC = True
"""The cyclic garbage collector is paused during a search: the search allocates
millions of small tuples, none of them in a cycle (reference counting frees them
all), and the collector's passes over them cost up to a third of the time on a
Blocksworld instance of 200 actions.  It is resumed when the search returns."""


@dataclass(frozen=True)
class Failure:
    """Why a task could not be carried out, at some depth below a top task."""

    depth: int
    path: tuple[str, ...]
    reason: str

    def __str__(self) -> str:
        return " > ".join(self.path) + f": {self.reason}"


@dataclass
class Result:
    """What a search gives back: the best plan (or None) and how the search went."""

    plan: Plan | None
    plans_found: int
    expansions: int
    complete: bool
    elapsed_ms: float
    failures: list[Failure] = field(default_factory=list)
    improvements: list[tuple[float, float]] = field(default_factory=list)
    first: bool = False
    """The search stopped at its first plan (satisficing) rather than looking for better."""

    def explain(self) -> str:
        """Why there is no plan: for each top task, the deepest point reached and what
        blocked it."""
        if self.plan is not None:
            return "a plan was found"
        if not self.failures:
            return "no plan: the search ran out of time before any task failed"
        return "\n".join(str(f) for f in self.failures)


def _label(name: str, args: tuple[Any, ...]) -> str:
    return f"{name}({', '.join(str(a) for a in args)})"


class Search:
    """One search for one problem (see the module's docstring)."""

    def __init__(self, problem: Problem,
                 on_improvement: Callable[[Plan], None] | None = None):
        self.problem = problem
        self.domain = problem.domain
        self.evaluator = Evaluator(problem)
        self.on_improvement = on_improvement
        self.ids = itertools.count(1)
        self.parents: dict[int, tuple[int | None, Any, int]] = {}
        """Each node's parent, label (a text, or a decomposition's task, arguments and
        decomposition name: formatted only when a failure is explained) and top task."""
        self.heads: dict[int, tuple[str, tuple, int]] = {}
        """Decomposition nodes: the task, its arguments, and the actions done before it."""
        self.failures: dict[int, Failure] = {}
        self.kinds = {e: problem.kind(e) for e in problem.entities}
        self.typed: dict[str, list[str]] = {}
        self.repeats = 0
        self.pruned = False

    # -- bookkeeping for explanations --------------------------------------------

    def _node(self, parent: int | None, label: Any, root: int) -> int:
        node = next(self.ids)
        self.parents[node] = (parent, label, root)
        return node

    def _fail(self, parent: int, label: str, reason: str) -> None:
        path = [label]
        node: int | None = parent
        root = 0
        while node is not None:
            up, text, root = self.parents[node]
            path.append(text if isinstance(text, str) else
                        f"{_label(text[0], text[1])}[{text[2]}]")
            node = up
        path.reverse()
        known = self.failures.get(root)
        if known is None or len(path) > known.depth:
            self.failures[root] = Failure(len(path), tuple(path), reason)

    def _of_type(self, kind: str) -> list[str]:
        found = self.typed.get(kind)
        if found is None:
            found = self.typed[kind] = self.problem.of_type(kind)
        return found

    # -- the search ------------------------------------------------------------------

    def run(self, budget_ms: float, first: bool = False) -> Result:
        """Search until the budget runs out, the space is exhausted, or (``first``) a plan
        is found; again with one more repetition allowed while left recursion was all that
        stood in the way (see the module's docstring)."""
        start = time.perf_counter()
        deadline = start + budget_ms / 1000.0
        collecting = gc.isenabled()
        if PAUSE_GC:
            gc.disable()
        try:
            while True:
                self.pruned = False
                self.failures = {}
                result = self._search(start, deadline, first)
                if (result.plan is not None or not result.complete or not self.pruned
                        or self.repeats >= MAX_REPEATS):
                    return result
                self.repeats += 1
        finally:
            if collecting:
                gc.enable()

    def _search(self, start: float, deadline: float, first: bool) -> Result:
        roots = [self._node(None, _label(name, args), index)
                 for index, (name, args) in enumerate(self.problem.tasks)]
        agenda = None
        for root, (name, args) in reversed(list(zip(roots, self.problem.tasks, strict=True))):
            agenda = ((name, args, root), agenda)
        initial = dict(self.problem.initial)
        state = (FactState(initial, self.domain.patterns) if self.domain.predicates
                 else State(initial))
        best: Plan | None = None
        best_score = float("inf")
        found = 0
        expansions = 0
        improvements: list[tuple[float, float]] = []
        stack: list[Iterator[tuple]] = []
        node: tuple | None = (state, agenda, None, 0.0, 0.0, 0.0, 0)
        complete = True
        bound = self.evaluator.lower_bound
        actions, methods = self.domain.actions, self.domain.methods
        while True:
            if node is None:  # back to the latest choice point
                if not stack:
                    break
                node = next(stack[-1], None)
                if node is None:
                    stack.pop()
                    continue
            expansions += 1
            if expansions % CHECK_EVERY == 0 and time.perf_counter() > deadline:
                complete = False
                break
            state, agenda, trail, cost, human, robot, steps = node
            node = None
            if best is not None and bound(cost, human, robot) >= best_score:
                continue
            if agenda is None:
                missed = [f"{fact_text(e, a)} == {v!r}"
                          for (e, a), v in self.problem.goals.items() if state.get(e, a) != v]
                if missed:
                    self.failures.setdefault(-1, Failure(0, ("goals",), "a decomposition of "
                                             "every task ends without " + ", ".join(missed)))
                    continue
                plan = self.evaluator.plan(trail, roots)
                found += 1
                if plan.score < best_score:
                    best, best_score = plan, plan.score
                    improvements.append(((time.perf_counter() - start) * 1000, plan.score))
                    if self.on_improvement is not None:
                        self.on_improvement(plan)
                if first:
                    complete = False
                    break
                continue
            (name, args, parent), rest = agenda
            action = actions.get(name)
            if action is not None:  # one successor at most: no choice point
                node = self._apply(action, args, parent, state, rest, trail, cost, human,
                                   robot, steps)
            else:
                stack.append(self._decompose(methods[name], args, parent, state, rest, trail,
                                             cost, human, robot, steps))
        elapsed = (time.perf_counter() - start) * 1000
        failures = [self.failures[k] for k in sorted(self.failures, key=lambda k: (k < 0, k))
                    ] if best is None else []
        return Result(best, found, expansions, complete, elapsed, failures, improvements,
                      first and best is not None)

    def _apply(self, action: Action, args: tuple, parent: int, state: State, rest: Any,
               trail: Any, cost: float, human: float, robot: float,
               steps: int) -> tuple | None:
        """The search node after ``action``, or None when it cannot be done (or dooms
        the plan: goal protection)."""
        env = dict(zip(action.names, args, strict=True))
        get = state.get
        if action.pre is not None and not action.pre.fn(env, get):
            self._fail(parent, _label(action.name, args),
                       f"precondition false: {action.pre.text}")
            return None
        price = action.cost(env, get) if callable(action.cost) else action.cost
        length = action.duration(env, get) if callable(action.duration) else action.duration
        child = state.child()
        action.apply(env, get, child.set)
        for pred, key in action.deletes:
            fact = key(env)
            if (self.problem.goals.get((pred, fact)) is True and get(pred, fact) is True
                    and child.get(pred, fact) is not True and not self._may_add(rest, pred, fact)):
                self._fail(parent, _label(action.name, args),
                           f"deletes ({' '.join((pred, *fact))}), a goal that no task left "
                           "can make true again")
                return None
        agent = SOLE_AGENT if action.agent is None else env[action.agent]
        kind = self.kinds.get(agent)
        node = next(self.ids)
        record = ("act", node, parent, action.name, args, agent, price, length)
        return (child, rest, (record, trail), cost + price,
                human + (price if kind == "human" else 0.0),
                robot + (price if kind == "robot" else 0.0), steps + 1)

    def _may_add(self, agenda: Any, pred: str, fact: tuple) -> bool:
        """Whether a task of ``agenda`` may make the fact true again (goal protection: a
        goal fact deleted for good dooms the branch, however far its end)."""
        may_add = self.domain.may_add
        while agenda is not None:
            (name, args, _), agenda = agenda
            if may_add(name, args, pred, fact):
                return True
        return False

    def _repeated(self, name: str, args: tuple, parent: int, steps: int) -> bool:
        """Whether decomposing ``name(args)`` now would repeat an ancestor's decomposition
        of it, in the same state, more than ``repeats`` times."""
        count = 0
        heads = self.heads
        node: int | None = parent
        while node is not None:
            head = heads.get(node)
            if head is None or head[2] != steps:
                return False
            if head[0] == name and head[1] == args:
                count += 1
                if count > self.repeats:
                    return True
            node = self.parents[node][0]
        return False

    def _decompose(self, method: Method, args: tuple, parent: int, state: State, rest: Any,
                   trail: Any, cost: float, human: float, robot: float,
                   steps: int) -> Iterator[tuple]:
        if self._repeated(method.name, args, parent, steps):
            self.pruned = True
            label = _label(method.name, args)
            self._fail(parent, label, f"left recursion: {label} again before any action "
                       f"(more than {self.repeats} time(s))")
            return
        env = {p: a for (p, _), a in zip(method.params, args, strict=True)}
        get = state.get
        ids, parents, heads = self.ids, self.parents, self.heads
        root = parents[parent][2]
        tried = []
        applied = False
        for dec in method.decompositions:
            if dec.bind is not None:
                candidates: Any = dec.bind(env, state)
            else:
                names = [v for v, _ in dec.vars]
                choices = [self._of_type(t) for _, t in dec.vars]
                candidates = (dict(zip(names, values, strict=True))
                              for values in itertools.product(*choices))
            matched = False
            for binding in candidates:
                local = {**env, **binding}
                if dec.bind is None and dec.pre is not None and not dec.pre(local, get):
                    continue
                matched = applied = True
                node = next(ids)
                parents[node] = (parent, (method.name, args, dec.name), root)
                heads[node] = (method.name, args, steps)
                agenda = rest
                for sub in reversed(dec.subtasks):
                    values = (sub.values(local) if sub.values is not None
                              else tuple([a.fn(local, get) for a in sub.args]))
                    agenda = ((sub.task, values, node), agenda)
                record = ("method", node, parent, method.name, args, dec.name, binding)
                yield (state, agenda, (record, trail), cost, human, robot, steps)
            if not matched:
                if dec.bind is None and dec.vars and not all(
                        self._of_type(t) for _, t in dec.vars):
                    tried.append(f"{dec.name}: no entity of type "
                                 f"{', '.join(t for _, t in dec.vars)}")
                else:
                    tried.append(f"{dec.name}: {dec.pre.text if dec.pre else 'no binding'}")
        if not applied:
            self._fail(parent, _label(method.name, args),
                       "no decomposition applies (" + "; ".join(tried) + ")")


def plan(problem: Problem, budget_ms: float | None = None,
         on_improvement: Callable[[Plan], None] | None = None, *, first: bool = False) -> Result:
    """Plan ``problem`` within ``budget_ms`` (default: the problem's own budget); with
    ``first``, stop at the first plan found."""
    budget = problem.budget_ms if budget_ms is None else budget_ms
    if problem.domain.predicates:  # HDDL: the IPC mode's depth-first search first
        from planner.depthfirst import first_plan, improve

        return (first_plan if first else improve)(problem, budget, on_improvement)
    return Search(problem, on_improvement).run(budget, first)

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
*anytime*: every complete plan is evaluated (:mod:`planner.evaluation.evaluate`); the
best so far is kept, reported to ``on_improvement``, and used to prune: a
partial plan whose lower bound (the monotone part of the score: cost and
effort so far) cannot beat it is abandoned.  When the time budget runs out,
the best plan found so far is returned.  With ``first=True`` (satisficing, as
in the IPC's HTN track) it stops at the first plan instead.

HDDL methods bind their free variables from the state's facts
(:class:`~planner.model.domain.Decomposition` ``bind``, :mod:`planner.search.binding`),
and their states index those facts (:class:`~planner.model.state.FactState`).
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

from planner.evaluation.evaluate import Evaluator
from planner.model.domain import Action, Method, Problem
from planner.model.plan import Plan, fact_text
from planner.model.state import FactState, State
from planner.search.bound import RemainingCost
from planner.search.step import Stepper, binder

CHECK_EVERY = 256
"""Expansions between two looks at the clock."""
MAX_REPEATS = 8
"""The most repetitions of a left-recursive decomposition the deepening allows."""
MAX_DEPTH = 10_000
"""The default decomposition-depth budget: how many tasks deep a decomposition may nest
below a top task.  Each level keeps its choice point and state alive; 10,000 levels is
tens of megabytes, where Blocksworld-GTOHP p30's plan of 6,660 actions nests 82 deep."""
MAX_NODES = 500_000
"""The default node budget: search nodes expanded plus variable bindings tried, over the
whole search.  Every node leaves a hundred-odd bytes behind (what explains a failure);
half a million answer within about 5 s and 200 MB even on a loaded machine, where the
proven best clean-up of six bottles with two agents takes some 120,000 (with three
agents, about 610,000: raise it)."""
SHOWN = 4
"""A failure's path longer than twice this shows its first and last tasks only."""
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
        path = self.path
        if len(path) > 2 * SHOWN + 1:  # a runaway recursion: its ends tell the story
            path = (*path[:SHOWN], f"... ({len(path) - 2 * SHOWN} more) ...",
                    *path[-SHOWN:])
        return " > ".join(path) + f": {self.reason}"


class BudgetExhausted(Exception):
    """A search budget ran out (raised inside the search, reported in :class:`Result`)."""

    def __init__(self, budget: str):
        super().__init__(budget)
        self.budget = budget


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
    applied: int = 0
    """Actions applied (precondition checked and true, effects applied), over the search."""
    exhausted: str | None = None
    """The search budget that ran out, in words (None: none did): the node budget
    stops the search; the depth budget cuts the branches that reach it."""

    def explain(self) -> str:
        """Why there is no plan: a budget that ran out, then, for each top task, the
        deepest point reached and what blocked it."""
        if self.plan is not None:
            return "a plan was found"
        lines = [] if self.exhausted is None else [
            f"search budget exhausted: {self.exhausted}"]
        if not self.failures and self.exhausted is None:
            lines.append("no plan: the search ran out of time before any task failed")
        lines.extend(str(f) for f in self.failures)
        return "\n".join(lines)


def _label(name: str, args: tuple[Any, ...]) -> str:
    return f"{name}({', '.join(str(a) for a in args)})"


def deleted_goal(problem: Problem, action: Action, env: dict, before: Callable,
                 child: Any, may_add: Callable, agenda: Any) -> str | None:
    """Why a step dooms its branch, if it does (goal protection): it deletes a goal fact
    that held, and no task left on ``agenda`` (``may_add(agenda, pred, fact)``) can
    make it true again, however far the branch's end.  Both searches ask this."""
    goals = problem.goals
    for pred, key in action.deletes:
        fact = key(env)
        if (goals.get((pred, fact)) is True and before(pred, fact) is True
                and child.get(pred, fact) is not True and not may_add(agenda, pred, fact)):
            return (f"deletes ({' '.join((pred, *fact))}), a goal that no task left "
                    "can make true again")
    return None


class Search:
    """One search for one problem (see the module's docstring)."""

    def __init__(self, problem: Problem,
                 on_improvement: Callable[[Plan], None] | None = None, *,
                 lookahead: bool = True, max_depth: int | None = None,
                 max_nodes: int | None = None):
        self.problem = problem
        self.max_depth = MAX_DEPTH if max_depth is None else max_depth
        self.max_nodes = MAX_NODES if max_nodes is None else max_nodes
        self.nodes = 0
        self.applied = 0
        """Nodes expanded and bindings tried so far, over every restart (the node budget)."""
        self.too_deep: str | None = None
        """The first task cut by the depth budget, if any."""
        self.domain = problem.domain
        self.evaluator = Evaluator(problem)
        self.stepper = Stepper(problem, self.evaluator)
        """Each action's step, compiled once: precondition, effects, and the floor, which
        grows with the rules' penalties as links and waits appear (:mod:`planner.search.step`)."""
        self.decomposition_floor = self.evaluator.decomposition_floor()
        remaining = RemainingCost(problem) if lookahead else None
        self.remaining = remaining if remaining is not None and remaining.enabled else None
        """The lower bound on what the agenda's tasks will cost (None: cost so far only)."""
        self.on_improvement = on_improvement
        self.ids = itertools.count(1)
        self.parents: dict[int, tuple[int | None, Any, int]] = {}
        """Each node's parent, label (a text, or a decomposition's task, arguments and
        decomposition name: formatted only when a failure is explained) and top task."""
        self.heads: dict[int, tuple[str, tuple, int]] = {}
        """Decomposition nodes: the task, its arguments, the actions done before it, and
        its depth (top tasks are at depth 0, their subtasks at 1 ...)."""
        self.failures: dict[int, Any] = {}
        """The deepest failure under each top task: (depth, parent, label, reason), or a
        :class:`Failure` (the goals)."""
        self.typed: dict[str, list[str]] = {}
        self.binders: dict[str, Callable[[tuple], dict]] = {}
        """Each method's variables from its arguments (:func:`planner.search.step.binder`)."""
        self.repeats = 0
        self.pruned = False

    # -- bookkeeping for explanations --------------------------------------------

    def _node(self, parent: int | None, label: Any, root: int) -> int:
        node = next(self.ids)
        self.parents[node] = (parent, label, root)
        return node

    def _fail(self, parent: int, label: str, reason: str) -> None:
        """Remember the failure if it is the deepest under its top task; its path is
        spelled out only at the end (:meth:`_failure`): a search that dives ten thousand
        tasks deep meets a deeper failure at every level."""
        head = self.heads.get(parent)
        depth = 2 if head is None else head[3] + 2
        root = self.parents[parent][2]
        known = self.failures.get(root)
        if known is None or depth > known[0]:
            self.failures[root] = (depth, parent, label, reason)

    def _failure(self, pending: tuple) -> Failure:
        """A remembered failure with its path, from the top task down."""
        if isinstance(pending, Failure):
            return pending
        depth, parent, label, reason = pending
        path = [label]
        node: int | None = parent
        while node is not None:
            up, text, _ = self.parents[node]
            path.append(text if isinstance(text, str) else
                        f"{_label(text[0], text[1])}[{text[2]}]")
            node = up
        path.reverse()
        return Failure(len(path), tuple(path), reason)

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
        node: tuple | None = (state, agenda, None, 0.0, 0)
        complete = True
        exhausted: str | None = None
        max_nodes = self.max_nodes
        per_cost = self.evaluator.cost_weight
        remaining = self.remaining if per_cost > 0 else None
        tops = set(roots)
        actions, methods = self.domain.actions, self.domain.methods
        while True:
            if node is None:  # back to the latest choice point
                if not stack:
                    break
                try:
                    node = next(stack[-1], None)
                except BudgetExhausted as out:
                    complete, exhausted = False, out.budget
                    break
                if node is None:
                    stack.pop()
                    continue
            expansions += 1
            self.nodes += 1
            if expansions % CHECK_EVERY == 0:
                if time.perf_counter() > deadline:
                    complete = False
                    break
                if self.nodes > max_nodes:
                    complete, exhausted = False, self._nodes_out()
                    break
            state, agenda, trail, floor, steps = node
            node = None
            if best is not None:
                if floor >= best_score:
                    continue
                if (remaining is not None and agenda is not None
                        and agenda[0][2] in tops and floor + per_cost * remaining.bound(
                            agenda, state, (best_score - floor) / per_cost) >= best_score):
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
                node = self._apply(action, args, parent, state, rest, trail, floor, steps)
            else:
                stack.append(self._decompose(methods[name], args, parent, state, rest, trail,
                                             floor, steps))
        elapsed = (time.perf_counter() - start) * 1000
        failures = [self._failure(self.failures[k])
                    for k in sorted(self.failures, key=lambda k: (k < 0, k))
                    ] if best is None else []
        if self.too_deep is not None:
            complete = False
            cut = self._depth_out()
            exhausted = cut if exhausted is None else f"{exhausted}; and {cut}"
        stack.clear()  # the choice points hold states: let them go before the result
        return Result(best, found, expansions, complete, elapsed, failures, improvements,
                      first and best is not None, self.applied, exhausted)

    def _nodes_out(self) -> str:
        return (f"the node budget ({self.max_nodes:,} nodes expanded and bindings tried) "
                "ran out; raise it with max_nodes= (shary plan --max-nodes N)")

    def _depth_out(self) -> str:
        return (f"the decomposition depth budget ({self.max_depth:,} nested tasks) cut the "
                f"search at {self.too_deep}; is a method recursive without end? Raise it "
                "with max_depth= (shary plan --max-depth N)")

    def _apply(self, action: Action, args: tuple, parent: int, state: State, rest: Any,
               trail: Any, floor: float, steps: int) -> tuple | None:
        """The search node after ``action``, or None when it cannot be done (or dooms
        the plan: goal protection).  ``floor`` is the partial plan's score so far: what
        no completion of it can go below."""
        for assignment in self.problem.assigned:
            performer = action.performer(dict(zip(action.names, args, strict=True)))
            if assignment.breaks(action.name, args, performer):
                self._fail(parent, _label(action.name, args),
                           f"{assignment.agent} does it (an assignment)")
                return None
        step = self.stepper.steps.get(action.name) or self.stepper.step(action)
        done = step(args, state, floor)
        if done is None:
            self._fail(parent, _label(action.name, args),
                       f"precondition false: {action.pre.text}")  # type: ignore[union-attr]
            return None
        child, env, price, length, agent, floor = done
        if action.deletes:
            why = deleted_goal(self.problem, action, env, state.get, child, self._may_add, rest)
            if why is not None:
                self._fail(parent, _label(action.name, args), why)
                return None
        self.applied += 1
        record = ("act", next(self.ids), parent, action.name, args, agent, price, length)
        return (child, rest, (record, trail), floor, steps + 1)

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
                   trail: Any, floor: float, steps: int) -> Iterator[tuple]:
        if self._repeated(method.name, args, parent, steps):
            self.pruned = True
            label = _label(method.name, args)
            self._fail(parent, label, f"left recursion: {label} again before any action "
                       f"(more than {self.repeats} time(s))")
            return
        heads = self.heads
        above = heads.get(parent)
        depth = 1 if above is None else above[3] + 1
        if depth > self.max_depth:
            if self.too_deep is None:
                self.too_deep = _label(method.name, args)
            return
        bind = self.binders.get(method.name)
        if bind is None:
            bind = self.binders[method.name] = binder(tuple(p for p, _ in method.params))
        env = bind(args)
        get = state.get
        ids, parents = self.ids, self.parents
        root = parents[parent][2]
        max_nodes = self.max_nodes
        tried = []
        applied = False
        for dec in method.decompositions:
            penalty = self.decomposition_floor.get((method.name, dec.name), 0.0)
            names = [v for v, _ in dec.vars]
            pre = dec.pre.fn if dec.bind is None and dec.pre is not None else None
            if dec.bind is not None:
                candidates: Any = dec.bind(env, state)
            else:
                candidates = itertools.product(*[self._of_type(t) for _, t in dec.vars])
            matched = False
            for binding in candidates:
                self.nodes += 1
                if self.nodes > max_nodes:
                    raise BudgetExhausted(self._nodes_out())
                local = env.copy()
                if dec.bind is None:  # values, in the order of the variables
                    local.update(zip(names, binding, strict=True))
                    if pre is not None and not pre(local, get):
                        continue
                    binding = dict(zip(names, binding, strict=True))
                else:
                    local.update(binding)
                matched = applied = True
                node = next(ids)
                parents[node] = (parent, (method.name, args, dec.name), root)
                heads[node] = (method.name, args, steps, depth)
                agenda = rest
                for sub in reversed(dec.subtasks):
                    values = (sub.values(local) if sub.values is not None
                              else tuple([a.fn(local, get) for a in sub.args]))
                    agenda = ((sub.task, values, node), agenda)
                record = ("method", node, parent, method.name, args, dec.name, binding)
                yield (state, agenda, (record, trail), floor + penalty, steps)
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


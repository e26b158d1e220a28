"""Depth-first total-order decomposition to the first plan: the search of the IPC mode.

The branch-and-bound search (:mod:`planner.search.branchbound`) scores every plan it meets
and keeps bookkeeping for that; the IPC 2020 HTN track, GTPyhop and the
track's total-order planners only want *a* plan, fast.  This search does what
they do -- the first task of the agenda is an action (its precondition is
checked, its effects applied) or a compound task (each method in file order,
each binding its binder proposes, replaces it by its subtasks) -- with the
prunings below, which keep recursive domains finite and fail early:

* **seen nodes**: a search node is its state and its agenda (the tasks left).
  Both are hashed incrementally (a state's hash is the XOR of its true facts'
  hashes, changed by each fact an action flips; an agenda's hash is a chain
  over its tasks), and a node whose pair was met before is not expanded again:
  what can follow a node depends on nothing else, so a node already expanded
  either led to the plan or failed.  This ends the random walks of tail
  recursion (Snake's ``move``, Transport's ``get_to``).
* **repeated decomposition**: decomposing a task (name and arguments) in the
  very state where one of its :data:`WINDOW` nearest ancestors decomposed the
  same task is refused more than ``repeats`` times (Satellite's ``do_switching`` that switches an
  instrument off and on to decompose itself again).  ``repeats`` starts at 0;
  when a pass ends without a plan and this refusal was used, the search starts
  again with one more, up to :data:`MAX_REPEATS` (as :mod:`planner.search.branchbound`
  does for left recursion), so a plan that needs repetitions is still found.
* **goal protection**, as in :mod:`planner.search.branchbound`: an action that deletes a
  goal fact no task left may add again ends its branch.
* **goals out of reach** (a problem with at most
  :data:`~planner.search.checks.FEW_GOALS` goal facts): a decomposition after which no
  task left may add a false goal fact that the decomposed task may add is refused; what
  a task may add is guarded by the constants its methods fix (``Domain.may_add``).
  Monroe's plan recognition has one goal, that the observed actions were done, and ten
  top-level methods of which one can do them.  The same check asks the chains of facts the goals
  need in order (:mod:`planner.heuristics.landmarks`): a stack that cannot add them in
  turn is refused, and the successors of a task that may add one of them are
  tried in the chains' order (in every pass).
* **doomed decompositions**: a decomposition is refused where it is chosen when
  one of its actions (arguments bound) needs a fact that is false and that no
  subtask before it may add, or deletes a fact that an action among the
  :data:`~planner.search.checks.LOOKAHEAD` tasks after it on the agenda needs, with no
  task in between that may add it again (a threat, in partial-order planning's words).
  Factories' ``m_get_resource`` may build a factory on the very plot the
  factory being built needs: without this, every way of fetching the resources
  in between is tried before that last step fails.
* **threats tried last**: a binding whose actions delete a true fact that an
  action among those tasks needs, though a task in between *may* add it again
  (so the threat is not proved), is tried after the other bindings of its
  decomposition.  Factories' deliveries may pick a resource up where it waits
  for a ``fuse``, which some later delivery might bring back but does not: the
  search then tried every way of doing what lies between before the ``fuse``
  failed.

These last three (:mod:`planner.search.checks`) check every decomposition; they cost
most problems more than they save, so a first pass of :data:`PLAIN_NODES`
nodes goes without them, and the search starts again with them only when that pass found no plan.

Early precondition checks are the binders' (:mod:`planner.search.binding`): a
method's variables are bound from its precondition, its first action's
precondition and the static facts every later action needs.

A search is bounded by a time budget, a **node budget** (:data:`MAX_NODES`
nodes by default) and a depth that grows with the problem: a pass cuts the
branches deeper than :data:`MAX_DEPTH` decompositions (a wrong choice high in
a recursive domain -- Logistics' learned methods -- is then left soon enough),
and when a pass ends without a plan because it cut some, the next allows
:data:`DEEPER` times more, up to :data:`DEEPEST` (Towers of Hanoi with 16 rings
needs 65,535 moves, nested about twice as deep).  A recursion that never ends
cannot allocate without bound; it ends with ``no plan`` and the explanation
``search budget exhausted``, then the deepest points reached.

The plan found is evaluated once, like the other search's (tree, streams,
causal links), so that the validator, the renderers and the IPC writer work on
it unchanged.
"""

from __future__ import annotations

import gc
import itertools
import time
from collections.abc import Callable, Iterator
from typing import Any

from planner.evaluation.evaluate import Evaluator
from planner.model.domain import SOLE_AGENT, Action, Method, Problem
from planner.model.plan import Plan, fact_text
from planner.model.state import FactState, State
from planner.search.branchbound import Failure, Result, deleted_goal
from planner.search.checks import DecompositionChecks, task_call
from planner.search.late import same, substitute

MAX_NODES = 2_000_000
"""Default node budget: search nodes expanded, over every pass, before giving up (the
set of nodes seen then holds about 100 MB)."""
MAX_DEPTH = 10_000
"""Deepest decomposition tree the first pass searches: a branch deeper than this is cut
(each level keeps a state and a choice point: about 6-13 KB)."""
DEEPER = 10
"""How much deeper each new pass may go, when the one before cut branches."""
DEEPEST = 1_000_000
"""The deepest any pass goes (several GB: in practice the time budget ends first)."""
SHOWN = 12
"""The most tasks an explanation shows on the path to a failure."""
WINDOW = 64
"""How many ancestors the repeated-decomposition check looks at (a loop of
decompositions longer than this is left to the budgets)."""
MAX_REPEATS = 4
"""The most repetitions of a decomposition in one state that the deepening allows."""
PLAIN_NODES = 20_000
"""The nodes of a first pass without the checks of decompositions (threats, goals out of
reach): most problems have their plan by then (Blocksworld-GTOHP's 1,000 blocks in
13,342), and would only pay for the checks; past them, the search starts again with
them."""
CHECK_EVERY = 256
"""Expansions between two looks at the clock."""
BUDGET_EXHAUSTED = "search budget exhausted"
"""How an explanation begins when the node budget ran out (the time budget has its own)."""


def first_plan(problem: Problem, budget_ms: float | None = None,
               on_improvement: Callable[[Plan], None] | None = None, *,
               max_nodes: int = MAX_NODES, hand_over: bool = False) -> Result:
    """The first plan of a depth-first search of ``problem`` (HDDL: its methods have
    binders), within ``budget_ms`` (default: the problem's) and ``max_nodes``;
    ``hand_over``: the search ends at the first branch it cuts, rather than going on and
    then deeper (:mod:`planner.search.portfolio`: another search takes the time left)."""
    budget = problem.budget_ms if budget_ms is None else budget_ms
    search = DepthFirst(problem)
    search.hand_over = hand_over
    return search.run(budget, max_nodes, on_improvement)


Path = tuple
"""Where a task sits in the tree being grown: ``(parent path or None, label, index of
its top task, hash of the state it was decomposed in or 0, node id, depth)``; the label is a
text for a top task, ``(task, args)`` for a decomposition.  Kept only by the agenda
entries below it, so that an abandoned branch frees its paths."""


def improve(problem: Problem, budget_ms: float | None = None,
            on_improvement: Callable[[Plan], None] | None = None) -> Result:
    """Anytime HDDL planning: the first plan of this search, then better ones from the
    branch-and-bound search (:mod:`planner.search.branchbound`) for what is left of the budget; the
    best plan of the two, with every improvement reported as it is found."""
    from planner.search.branchbound import Search

    budget = problem.budget_ms if budget_ms is None else budget_ms
    start = time.perf_counter()
    best: list[Plan] = []

    def better(plan: Plan) -> None:
        if not best or plan.score < best[-1].score:
            best.append(plan)
            if on_improvement is not None:
                on_improvement(plan)

    first = first_plan(problem, budget, better)
    left = budget - (time.perf_counter() - start) * 1000
    if first.plan is None or left <= 0:
        return first
    more = Search(problem, better).run(left)
    plan = best[-1]
    elapsed = (time.perf_counter() - start) * 1000
    return Result(plan, first.plans_found + more.plans_found,
                  first.expansions + more.expansions, more.complete, elapsed, [],
                  [*first.improvements, *((first.elapsed_ms + t, score)
                                          for t, score in more.improvements
                                          if score < first.plan.score)])


class _Stop(Exception):
    """The node or time budget ran out."""


class DepthFirst:
    """One depth-first search for one problem (see the module's docstring)."""

    def __init__(self, problem: Problem):
        self.problem = problem
        self.domain = problem.domain
        self.goals = tuple((pred, args, value) for (pred, args), value in problem.goals.items())
        self.ids = itertools.count(1)
        self.failures: dict[int, tuple[int, Path, str, str]] = {}
        """For each top task, the deepest failure: its depth, parent, label and reason."""
        self.repeats = 0
        self.repeated = False
        self.careful = False
        """Whether decompositions are checked (:mod:`planner.search.checks`): not
        in the first :data:`PLAIN_NODES` nodes, which find the plans of most problems."""
        self.cut = False
        """A branch was cut at ``max_depth`` in the last pass."""
        self.max_depth = MAX_DEPTH
        self.decomposed: set[int] = set()
        """The (task, arguments, state) hashes of every decomposition made so far."""
        self.ground: dict[tuple[str, tuple], dict[str, list[dict[str, str]]]] | None = None
        """The ground model's bindings of the methods that leave a variable to its type
        (:attr:`planner.heuristics.grounding.Grounded.bindings`), when a search has them: those
        decompose the task, each checked against the method's precondition in the
        state, rather than the binder (AssemblyHierarchical's ``m1``: the 240 pairs of
        ports some ``connect_k`` may join, not the 14,400 pairs of ports)."""
        self.missed = ""
        """The goals the first complete decomposition missed (when one did)."""
        self.expansions = 0
        self.checks = DecompositionChecks(self.domain, self.goals)
        """The checks of decompositions (:mod:`planner.search.checks`)."""
        self.defer = True
        """With the late binders: whether a method's variables that its own conditions do
        not read are left unbound (:mod:`planner.search.late`)."""
        self.hand_over = False
        """Whether the first branch cut ends the search (:func:`first_plan`)."""

    # -- explanations ------------------------------------------------------------------

    def _fail(self, parent: Path, label: str, reason: str) -> None:
        """Keep, for each top task, the deepest point where the search got stuck (as it is:
        it is put in words only if the search ends without a plan)."""
        root, depth = parent[2], parent[5] + 2
        known = self.failures.get(root)
        if known is None or depth > known[0]:
            self.failures[root] = (depth, parent, label, reason)

    def _failure(self, depth: int, parent: Path, label: str, reason: str) -> Failure:
        """A kept failure in words: the path from its top task, the middle of a very deep
        one left out."""
        path = [label]
        node: Path | None = parent
        while node is not None:
            node, text, _, _, _, _ = node
            path.append(text if isinstance(text, str) else task_call(*text))
        path.reverse()
        if len(path) > SHOWN:
            path[SHOWN // 2:-SHOWN // 2] = [f"... ({len(path) - SHOWN} more) ..."]
        return Failure(depth, tuple(path), reason)

    # -- the search ----------------------------------------------------------------------

    def run(self, budget_ms: float, max_nodes: int,
            on_improvement: Callable[[Plan], None] | None = None) -> Result:
        start = time.perf_counter()
        deadline = start + budget_ms / 1000.0
        collecting = gc.isenabled()
        gc.disable()  # millions of acyclic tuples: see planner.search.branchbound.PAUSE_GC
        stopped = ""
        trail, roots = None, []
        try:
            while True:
                self.repeated = False
                self.failures = {}
                try:
                    trail, roots = self._search(deadline, max_nodes)
                except _Stop as stop:
                    if str(stop) == "plain":  # no plan in the first nodes: start again checking
                        self.careful = True
                        continue
                    stopped = str(stop)
                    break
                if trail is not None:
                    break
                if self.cut and self.max_depth < DEEPEST:  # cut, not refuted: go deeper
                    self.max_depth = min(self.max_depth * DEEPER, DEEPEST)
                    self.cut = False
                    continue
                if not self.repeated or self.repeats >= MAX_REPEATS:
                    break
                self.repeats += 1
        finally:
            if collecting:
                gc.enable()
        plan = None
        if trail is not None:
            plan = Evaluator(self.problem).plan(trail[1], roots)
            if on_improvement is not None:
                on_improvement(plan)
        elapsed = (time.perf_counter() - start) * 1000
        return self._outcome(plan, stopped, elapsed, budget_ms, max_nodes)

    def _outcome(self, plan: Plan | None, stopped: str, elapsed: float, budget_ms: float,
                 max_nodes: int) -> Result:
        """The result of a search that ended with ``plan`` (or none: then the failures
        kept, in words, after the budget that ran out, ``stopped``: "nodes", "time" or
        "")."""
        failures = [] if plan is not None else [
            self._failure(*self.failures[k]) for k in sorted(self.failures)]
        if plan is None and self.missed:
            failures.append(Failure(0, ("goals",), "a decomposition of every task ends "
                                    "without " + self.missed))
        if plan is None and (stopped or self.cut):
            why = {"nodes": f"the node budget ({max_nodes}) ran out",
                   "time": f"the time budget ({budget_ms:g} ms) ran out",
                   "": f"branches deeper than {self.max_depth} decompositions were cut",
                   "cut": f"a branch deeper than {self.max_depth} decompositions was cut"
                   }[stopped]
            failures.insert(0, Failure(0, (BUDGET_EXHAUSTED,), (
                f"{why} after {self.expansions} search nodes, without a plan; the deepest "
                "points reached follow")))
        improvements = [(elapsed, plan.score)] if plan is not None else []
        return Result(plan, int(plan is not None), self.expansions,
                      plan is None and not stopped and not self.cut, elapsed, failures,
                      improvements,
                      first=plan is not None)

    def _start(self, patterns: Any = None) -> tuple[list[int], tuple]:
        """The ids of the top tasks and the first search node (the initial state, the
        problem's tasks as the agenda; the search that plans from it makes the rest);
        ``patterns``: the state's fact indexes, when not the domain's."""
        problem = self.problem
        tops = [(None, task_call(name, args), index, 0, next(self.ids), 0)
                for index, (name, args) in enumerate(problem.tasks)]
        roots = [top[4] for top in tops]
        agenda = None
        for top, (name, args) in reversed(list(zip(tops, problem.tasks, strict=True))):
            agenda = (name, args, top, hash((name, args, agenda[3] if agenda else 0)), agenda)
        initial = dict(problem.initial)
        state: State = (FactState(initial, patterns or self.domain.patterns)
                        if self.domain.predicates else State(initial))
        state_hash = 0
        for key, value in initial.items():
            if value:
                state_hash ^= hash(key)
        return roots, (state, state_hash, agenda, None)

    def _search(self, deadline: float, max_nodes: int) -> tuple[Any, list[int]]:
        """One pass; the trail of the first plan (or None) and the ids of the top tasks."""
        roots, first = self._start()
        seen: set[int] = set()
        stack: list[Iterator[tuple]] = []
        node: tuple | None = first
        actions, methods = self.domain.actions, self.domain.methods
        while True:
            if node is None:
                if not stack:
                    return None, roots
                node = next(stack[-1], None)
                if node is None:
                    stack.pop()
                    continue
            self.expansions += 1
            if self.expansions >= max_nodes:
                raise _Stop("nodes")
            if self.expansions == PLAIN_NODES and not self.careful:
                raise _Stop("plain")
            if self.expansions % CHECK_EVERY == 0 and time.perf_counter() > deadline:
                raise _Stop("time")
            state, state_hash, agenda, trail = node
            node = None
            if agenda is None:
                missed = [f"{fact_text(p, a)} == {v!r}" for p, a, v in self.goals
                          if state.get(p, a) != v]
                if not missed:
                    return (None, trail), roots
                self.missed = self.missed or ", ".join(missed)
                continue
            name, args, parent, agenda_hash, rest = agenda
            action = actions.get(name)
            if action is not None:  # one successor at most: no choice point
                node = self._apply(action, args, parent, state, state_hash, rest, trail)
            else:
                # A loop goes through a decomposition: the nodes seen are those.
                key = hash((state_hash, agenda_hash))
                if key in seen:
                    self._fail(parent, task_call(name, args),
                               "searched before, in this very state (a loop)")
                    continue
                seen.add(key)
                successors = self._decompose(methods[name], args, parent, state, state_hash,
                                             rest, trail)
                chains = self.checks.chains
                if chains and chains.may_add_any(name, args):
                    successors = chains.ordered(successors, rest, state.get)
                stack.append(successors)

    def _apply(self, action: Action, args: tuple, parent: Path, state: State, state_hash: int,
               rest: Any, trail: Any) -> tuple | None:
        """The node after ``action``, or None when it cannot be done (or dooms the plan)."""
        env = dict(zip(action.names, args, strict=True))
        get = state.get
        if action.pre is not None and not action.pre.fn(env, get):
            self._fail(parent, task_call(action.name, args),
                       f"precondition false: {action.pre.text}")
            return None
        writes: dict[tuple[str, Any], Any] = {}

        def put(entity: str, attribute: Any, value: Any) -> None:
            writes[(entity, attribute)] = value

        action.apply(env, get, put)
        child = state.child()
        for (pred, fact), value in writes.items():
            if bool(value) != bool(get(pred, fact)):
                state_hash ^= hash((pred, fact))
                child.set(pred, fact, value)
        if action.deletes:
            why = deleted_goal(self.problem, action, env, get, child, self._may_add, rest)
            if why is not None:
                self._fail(parent, task_call(action.name, args), why)
                return None
        agent = SOLE_AGENT if action.agent is None else env[action.agent]
        price = action.cost(env, get) if callable(action.cost) else action.cost
        length = action.duration(env, get) if callable(action.duration) else action.duration
        record = ("act", next(self.ids), parent[4], action.name, args, agent, price, length)
        return child, state_hash, rest, (record, trail)

    def _may_add(self, agenda: Any, pred: str, fact: tuple) -> bool:
        may_add = self.domain.may_add
        while agenda is not None:
            name, args, _, _, agenda = agenda
            if may_add(name, args, pred, fact):
                return True
        return False

    def _repeats(self, name: str, args: tuple, parent: Path, state_hash: int) -> bool:
        """Whether an ancestor decomposed ``name(args)`` in this very state more than
        ``repeats`` times already (the ancestors are looked at only when the search
        decomposed that task in that state somewhere before)."""
        key = hash((name, args, state_hash))
        if key not in self.decomposed:
            self.decomposed.add(key)
            return False
        count = 0
        node: Path | None = parent
        for _ in range(WINDOW):
            if node is None:
                break
            node, label, _, at, _, _ = node
            if at == state_hash and label == (name, args) and same(label[1], args):
                count += 1
                if count > self.repeats:
                    return True
        return False

    def _decompose(self, method: Method, args: tuple, parent: Path, state: State,
                   state_hash: int, rest: Any, trail: Any, late: bool = False
                   ) -> Iterator[tuple]:
        """The successors of decomposing ``method(args)``; ``late``: with the late binders
        (:mod:`planner.search.late`: variables left unbound, placeholders among ``args`` bound
        and replaced throughout the stack, a ``bind`` record in the trail)."""
        if self._repeats(method.name, args, parent, state_hash):
            self.repeated = True
            label = task_call(method.name, args)
            self._fail(parent, label, f"{label} again in the state where an ancestor "
                       "decomposed it (left recursion, or actions that change nothing), more "
                       f"than {self.repeats} time(s)")
            return
        depth = parent[5] + 1
        if depth > self.max_depth:
            self.cut = True
            self._fail(parent, task_call(method.name, args),
                       f"deeper than {self.max_depth} decompositions: cut")
            if self.hand_over:
                raise _Stop("cut")
            return
        env = {p: a for (p, _), a in zip(method.params, args, strict=True)}
        root = parent[2]
        tried = []
        known = None if self.ground is None else self.ground.get((method.name, args))
        for dec in method.decompositions:
            matched = False
            risky: list[tuple] = []
            assert dec.bind is not None, "the depth-first search plans HDDL methods"
            ground = None if known is None else known.get(dec.name)
            if ground is not None:
                bindings = _holding(dec, env, ground, state)
                if late:
                    bindings = ((binding, None) for binding in bindings)
            elif late:
                bindings = dec.late(env, state, self.defer)
            else:
                bindings = dec.bind(env, state)
            bindings = iter(bindings)
            following = next(bindings, None)
            while following is not None:
                binding, following = following, next(bindings, None)
                matched = True
                subst = None
                if late:
                    binding, subst = binding
                local = {**env, **binding}
                node = (parent, (method.name, args), root, state_hash, next(self.ids), depth)
                agenda = substitute(rest, subst) if subst else rest
                for sub in reversed(dec.subtasks):
                    values = (sub.values(local) if sub.values is not None
                              else tuple([a.fn(local, state.get) for a in sub.args]))
                    agenda = (sub.task, values, node,
                              hash((sub.task, values, agenda[3] if agenda else 0)), agenda)
                why = None
                if self.careful:
                    checks = self.checks
                    why = ((checks.doomed(agenda, len(dec.subtasks), state)
                            if checks.checked(dec) else None)
                           or (checks.unreachable(method.name, args, agenda, state)
                               if checks.few_goals else None))
                if why is not None:
                    self._fail(parent, task_call(method.name, args), f"{dec.name}: {why}")
                    continue
                record = ("method", node[4], parent[4], method.name, args, dec.name, binding)
                child = state, state_hash, agenda, (record, (("bind", subst), trail)
                                                    if subst else trail)
                if (following is not None and self.careful and checks.checked(dec)
                        and checks.risky(agenda, len(dec.subtasks), state)):
                    risky.append(child)
                    continue
                yield child
            yield from risky
            if not matched:
                tried.append(f"{dec.name}: {dec.pre.text if dec.pre else 'no binding'}")
        if tried and len(tried) == len(method.decompositions):
            self._fail(parent, task_call(method.name, args),
                       "no decomposition applies (" + "; ".join(tried) + ")")


def _holding(dec: Any, env: dict[str, Any], bindings: list[dict[str, str]],
             state: State) -> Iterator[dict[str, str]]:
    """The ground bindings of a decomposition whose precondition holds in ``state``."""
    pre = dec.pre
    for binding in bindings:
        if pre is None or pre.fn({**env, **binding}, state.get):
            yield binding

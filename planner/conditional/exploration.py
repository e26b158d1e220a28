"""Conditional plans: the robot plans its choices, the humans' choices become branches.

HATP/EHDA (Buisan et al.; JAHRVIS, section VI-C) gives each agent its own
agenda and lets them take turns: the robot's turn is the planner's to decide
(an **OR** node: every decomposition and binding is tried, the best kept), a
human's turn is not (an **AND** node: every action the human's agenda allows
at that point is a branch the plan must answer).  A human with nothing
applicable *waits*; an agent whose agenda is empty *idles*.  The branch ends
when every controlled agent's agenda is empty -- and, if the problem has
goals, they must hold there.

:func:`explore` builds that AND/OR graph.  It is a DAG: a turn reached again
with the same state, agendas and open values is explored once (the memo), and
a turn that comes back to itself on its own path (a wait loop that changes
nothing) is a dead end, not an endless branch (what such a cut, or the step
budget's, decided is not remembered: it depends on the way the turn was
reached).  An AND node is dead as soon as
one of its options is: the plan must answer every human choice (HATP/EHDA
silently drops such options; docs/benchmarks.md).  Choosing the policy --
costs, expected or worst case, social rules per branch -- is
:mod:`planner.conditional.policy`.

**Open values** (AgentX, query parameters: :class:`~planner.model.domain.OpenVar`)
are planned in lockstep: a turn holds a *bundle* of states, one for each
assignment of the open values bound so far, and an action must apply in every
one.  So the plan holds whichever capable agent acts, whatever the query
returns, as long as it is one of the candidates the plan lists.
"""

from __future__ import annotations

import itertools
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from planner.model.domain import Action, Decomposition, Method, Problem
from planner.model.state import State

IDLE = "IDLE"
WAIT = "WAIT"
DONE = "DONE"
MARK = "/"
"""The agenda entry ``("/Name", ())`` ends a task of a method some decomposition may
``abandon``: what is left of it lies before the mark."""
"""The step that ends a branch: the last controlled agenda drained (it costs nothing)."""
DEFAULT_MAX_STEPS = 400
MAX_STEPS = 2000
"""The most turns a branch may have (the schema's bound on ``max_steps``)."""
DEFAULT_MAX_NODES = 200_000
_ABSENT = object()
_EXPANSIONS_PER_TURN = 10_000
"""Decompositions one turn may go through before it reaches an action (a method that
decomposes into itself forever is cut there)."""


@dataclass(frozen=True)
class OpenValue:
    """A parameter the plan leaves to execution time: who does it (AgentX) or what a
    query returns, among ``candidates``."""

    var: str
    kind: str
    candidates: tuple[str, ...]
    query: str
    where: str
    """The task it was opened in and the step of the branch (its identity)."""

    def __str__(self) -> str:
        if self.kind == "agentx":
            return f"any-of[{', '.join(self.candidates)}]"
        return f"?{self.var}"

    def as_json(self) -> dict[str, Any]:
        if self.kind == "agentx":
            return {"any-of": list(self.candidates)}
        return {"query": self.query, "var": self.var, "candidates": list(self.candidates)}


Assignment = tuple[tuple[OpenValue, str], ...]
Entry = tuple[State, Assignment]
Bundle = tuple[Entry, ...]
Task = tuple[str, tuple[Any, ...]]
Agenda = tuple[Task, ...]


@dataclass(frozen=True)
class Expansion:
    """A decomposition the agent's agenda went through before its action."""

    method: str
    args: tuple[Any, ...]
    decomposition: str
    bindings: tuple[tuple[str, Any], ...]
    subtasks: int
    """Agenda entries it put in the task's place (its subtasks, and the end mark)."""
    dropped: int = 0
    """Agenda entries after them it abandoned."""


@dataclass(frozen=True)
class Step:
    """An action of a branch (or IDLE, WAIT), with the decompositions that led to it."""

    agent: str
    name: str
    args: tuple[Any, ...]
    cost: float
    duration: float
    expansions: tuple[Expansion, ...] = ()
    weight: float = 1.0
    """Its option's weight, when it is one of a human's options."""
    assigned: tuple[tuple[str, int], ...] = ()
    """How many tasks the action put at the head of which agent's agenda."""

    def __str__(self) -> str:
        return f"{self.name}({', '.join(str(a) for a in self.args)})"


@dataclass(eq=False)
class Turn:
    """A node of the AND/OR graph: whose turn, and each option with what follows."""

    agent: str
    kind: str
    """``or`` (the planner chooses), ``and`` (a human chooses), ``leaf`` (done)."""
    children: list[tuple[Step, Turn]] = field(default_factory=list)


LEAF_KIND = "leaf"


@contextmanager
def deep(steps: int) -> Iterator[None]:
    """Room for a recursion as deep as a branch of ``steps`` turns (a few frames a turn).
    The calls are Python to Python, which Python 3.11 makes without the C stack; the
    schema bounds ``max_steps``."""
    old = sys.getrecursionlimit()
    sys.setrecursionlimit(max(old, 4 * steps + 1000))
    try:
        yield
    finally:
        sys.setrecursionlimit(old)


class BudgetExhausted(Exception):
    """The node budget ran out: the exploration stops."""


@dataclass
class Exploration:
    """What :func:`explore` found: the root (None: no conditional plan) and counts."""

    root: Turn | None
    order: tuple[str, ...]
    controlled: frozenset[str]
    nodes: int
    cut: int
    """Branches cut by the step budget (``max_steps``)."""
    loops: int
    """Turns that came back to themselves on their own branch."""
    exhausted: str | None = None
    dead_ends: list[str] = field(default_factory=list)
    """A few places where no option was left, for the explanation."""
    max_steps: int = DEFAULT_MAX_STEPS
    """The step budget it ran with (turns per branch)."""


@dataclass
class _Option:
    expansions: tuple[Expansion, ...]
    action: Action | None
    args: tuple[Any, ...]
    weight: float
    agenda: Agenda
    bundle: Bundle
    cost: float = 0.0
    duration: float = 0.0
    assigned: tuple[tuple[str, Agenda], ...] = ()


def marked_methods(problem: Problem) -> frozenset[str]:
    """The methods some decomposition may abandon: their tasks end with a mark."""
    return frozenset(d.abandon for m in problem.domain.methods.values()
                     for d in m.decompositions if d.abandon)


class Explorer:
    """The AND/OR search of one conditional problem."""

    def __init__(self, problem: Problem, max_steps: int | None = None,
                 max_nodes: int | None = None, worst: bool = False, merge: bool = True):
        self.problem = problem
        self.domain = problem.domain
        self.order = tuple(agent for agent, _ in problem.agendas)
        uncontrolled = set(self.domain.uncontrolled)
        self.controlled = frozenset(a for a in self.order
                                    if problem.kind(a) not in uncontrolled)
        policy = problem.policy
        self.idle_cost = float(policy.get("idle_cost", 0.0))
        self.wait_cost = float(policy.get("wait_cost", 1.0))
        self.max_steps = min(int(max_steps or policy.get("max_steps", DEFAULT_MAX_STEPS)),
                             MAX_STEPS)
        self.max_nodes = int(max_nodes or DEFAULT_MAX_NODES)
        self.worst = worst
        self.merge = merge
        """Whether a turn reached again is explored once (False: the tree HATP/EHDA
        explores, for comparison)."""
        self.nodes = 0
        self.cut = 0
        self.loops = 0
        self.memo: dict[tuple, Turn | None] = {}
        self.active: set[tuple] = set()
        self.dead_ends: list[str] = []
        self.marked = marked_methods(problem)
        self.initial = problem.initial
        """Turns are remembered by how their states differ from it (small keys)."""

    # -- the turns -----------------------------------------------------------------------

    def run(self) -> Exploration:
        state = State({}, dict(self.problem.initial))
        agendas = tuple(tasks for _, tasks in self.problem.agendas)
        exhausted = None
        try:
            with deep(self.max_steps):
                root = self._turn(((state, ()),), agendas, 0, 0) if self.order else None
        except BudgetExhausted:
            root = None
            exhausted = (f"node budget: {self.max_nodes:,} turns and decompositions "
                         "explored (raise it with --max-nodes)")
        return Exploration(root, self.order, self.controlled, self.nodes, self.cut,
                           self.loops, exhausted, self.dead_ends, self.max_steps)

    def _tick(self) -> None:
        self.nodes += 1
        if self.nodes > self.max_nodes:
            raise BudgetExhausted

    def _turn(self, bundle: Bundle, agendas: tuple[Agenda, ...], t: int,
              steps: int) -> Turn | None:
        initial = self.initial
        key = (tuple((frozenset(kv for kv in s.items().items()
                                if initial.get(kv[0], _ABSENT) != kv[1]), a)
                     for s, a in bundle), agendas, t)
        if key in self.memo:
            return self.memo[key]
        if key in self.active:
            self.loops += 1
            return None
        if steps >= self.max_steps:
            self.cut += 1
            return None
        self._tick()
        self.active.add(key)
        cuts = self.loops + self.cut
        try:
            node = self._expand(bundle, agendas, t, steps)
        finally:
            self.active.discard(key)
        # What a loop or the step budget cut below it depends on how it was reached: it
        # is remembered only when nothing was.
        if self.merge and self.loops + self.cut == cuts:
            self.memo[key] = node
        return node

    def _expand(self, bundle: Bundle, agendas: tuple[Agenda, ...], t: int,
                steps: int) -> Turn | None:
        agent = self.order[t]
        controlled = agent in self.controlled
        nxt = (t + 1) % len(self.order)
        if controlled and not agendas[t] and self._done(agendas):
            return self._leaf(bundle)
        node = Turn(agent, "or" if controlled else "and")
        options = list(self._options(agent, agendas[t], bundle)) if agendas[t] else []
        if not options:
            if agendas[t]:
                if controlled:
                    self._dead(f"{agent}: nothing applicable for {_head(agendas[t])}")
                    return None
                step = Step(agent, WAIT, (), self.wait_cost, 0.0)
            else:
                step = Step(agent, IDLE, (), self.idle_cost, 0.0)
            child = self._turn(bundle, agendas, nxt, steps + 1)
            if child is None:
                return None
            node.children.append((step, child))
            return node
        for option in options:
            new = agendas[:t] + (option.agenda,) + agendas[t + 1:]
            for target, tasks in option.assigned:
                if target not in self.order:
                    self._dead(f"{target} is given tasks but has no agenda in the problem")
                    new = None
                    break
                at = self.order.index(target)
                new = new[:at] + (tasks + new[at],) + new[at + 1:]
            if new is None:
                continue
            handed = tuple((target, len(tasks)) for target, tasks in option.assigned)
            if option.action is None:  # the agenda drained through empty decompositions
                if controlled and self._done(new):
                    step = Step(agent, DONE, (), 0.0, 0.0, option.expansions, option.weight)
                    child: Turn | None = self._leaf(option.bundle)
                else:
                    step = Step(agent, IDLE, (), self.idle_cost, 0.0, option.expansions,
                                option.weight)
                    child = self._turn(option.bundle, new, nxt, steps + 1)
            else:
                step = Step(agent, option.action.name, option.args, option.cost,
                            option.duration, option.expansions, option.weight, handed)
                child = self._turn(option.bundle, new, nxt, steps + 1)
            if child is None:
                if not controlled:
                    self._dead(f"{agent} may do {step}, and then no plan is left")
                    return None
                continue
            node.children.append((step, child))
        return node if node.children else None

    def _done(self, agendas: tuple[Agenda, ...]) -> bool:
        return all(not agendas[i] for i, a in enumerate(self.order) if a in self.controlled)

    def _leaf(self, bundle: Bundle) -> Turn | None:
        for state, assignment in bundle:
            for (entity, attribute), wanted in self.problem.goals.items():
                if state.get(entity, attribute) != wanted:
                    self._dead(f"goal {entity}.{attribute} == {wanted!r} does not hold"
                               + (f" with {_assigned(assignment)}" if assignment else ""))
                    return None
        return Turn("", LEAF_KIND)

    def _dead(self, why: str) -> None:
        if len(self.dead_ends) < 20 and why not in self.dead_ends:
            self.dead_ends.append(why)

    # -- one agent's options -------------------------------------------------------------

    def _options(self, agent: str, agenda: Agenda, bundle: Bundle) -> Iterator[_Option]:
        """Every way the agent's agenda reaches its next action (or drains), in the
        domain's order: decompositions in file order, bindings in name order."""
        stack: list[tuple[Agenda, tuple[Expansion, ...], float, Bundle]] = [
            (agenda, (), 1.0, bundle)]
        budget = _EXPANSIONS_PER_TURN
        while stack:
            agenda, expansions, weight, bundle = stack.pop()
            if not agenda:
                yield _Option(expansions, None, (), weight, (), bundle)
                continue
            budget -= 1
            if budget < 0:
                self._dead(f"{agent}: more than {_EXPANSIONS_PER_TURN:,} decompositions "
                           f"before an action (a method that decomposes into itself?)")
                return
            self._tick()
            (name, args), rest = agenda[0], agenda[1:]
            if name.startswith(MARK):  # the end of a task: nothing to do
                stack.append((rest, expansions + (Expansion(name, (), "", (), 0),), weight,
                              bundle))
                continue
            action = self.domain.actions.get(name)
            if action is not None:
                applied = self._apply(action, args, bundle)
                if applied is not None:
                    child, cost, duration = applied
                    yield _Option(expansions, action, args, weight, rest, child, cost, duration,
                                  self._assigned(action, args, child))
                continue
            method = self.domain.methods[name]
            found = list(self._decompose(method, args, bundle))
            for dec, bindings, subtasks, new_bundle in reversed(found):
                kept = rest
                if dec.abandon is not None:
                    end = (MARK + dec.abandon, ())
                    if end not in rest:
                        self._dead(f"{name}[{dec.name}] abandons {dec.abandon}, which it is "
                                   "not part of")
                        continue
                    kept = rest[rest.index(end) + 1:]
                exp = Expansion(name, args, dec.name, bindings, len(subtasks),
                                len(rest) - len(kept))
                stack.append((subtasks + kept, expansions + (exp,), weight * dec.weight,
                              new_bundle))

    def _apply(self, action: Action, args: tuple, bundle: Bundle
               ) -> tuple[Bundle, float, float] | None:
        """The bundle after the action, and its cost and duration (the mean over the
        assignments, or the worst), or None if it does not apply in every one."""
        out = []
        costs = []
        durations = []
        for state, assignment in bundle:
            env = dict(zip(action.names, _resolve(args, assignment), strict=True))
            get = state.get
            if action.pre is not None and not action.pre.fn(env, get):
                return None
            child = state.child()
            action.apply(env, get, child.set)
            costs.append(_number(action.cost, env, get))
            durations.append(_number(action.duration, env, get))
            out.append((child, assignment))
        if self.worst:
            return tuple(out), max(costs), max(durations)
        return tuple(out), sum(costs) / len(costs), sum(durations) / len(durations)

    def _assigned(self, action: Action, args: tuple, bundle: Bundle
                  ) -> tuple[tuple[str, Agenda], ...]:
        """The tasks the action hands to other agents, their arguments evaluated after it
        (in the first state of the bundle: they name entities, not open values)."""
        if not action.assigns:
            return ()
        state, assignment = bundle[0]
        env = dict(zip(action.names, _resolve(args, assignment), strict=True))
        return tuple((env[param], tuple((sub.task, tuple(a(env, state.get) for a in sub.args))
                                        for sub in subtasks))
                     for param, subtasks in action.assigns)

    def _decompose(self, method: Method, args: tuple, bundle: Bundle
                   ) -> Iterator[tuple[Decomposition, tuple, Agenda, Bundle]]:
        base = dict(zip((p for p, _ in method.params), args, strict=True))
        for dec in method.decompositions:
            opened = {o.var: o for o in dec.open}
            closed = [(v, k) for v, k in dec.vars if v not in opened]
            pools = [self.problem.of_type(k) for _, k in closed]
            for values in itertools.product(*pools):
                self._tick()
                env = {**base, **dict(zip((v for v, _ in closed), values, strict=True))}
                if opened:
                    result = self._open(method, dec, env, args, bundle)
                    if result is None:
                        continue
                    env, new_bundle = result
                else:
                    if dec.pre is not None and not all(
                            dec.pre.fn(_env(env, a), s.get) for s, a in bundle):
                        continue
                    new_bundle = bundle
                subtasks = self._subtasks(dec, env, new_bundle)
                if subtasks is None:
                    continue
                if method.name in self.marked:
                    subtasks += ((MARK + method.name, ()),)
                bindings = tuple((v, env[v]) for v, _ in dec.vars)
                yield dec, bindings, subtasks, new_bundle
                if method.first:
                    return

    def _subtasks(self, dec: Decomposition, env: dict, bundle: Bundle) -> Agenda | None:
        """The decomposition's subtasks, their arguments evaluated in each state of the
        bundle: None (with a dead end said) if they differ -- one plan for every
        assignment of the open values needs the same tasks in all of them."""
        found = None
        for state, _ in bundle:
            subtasks = tuple((sub.task, tuple(arg(env, state.get) for arg in sub.args))
                             for sub in dec.subtasks)
            if found is None:
                found = subtasks
            elif subtasks != found:
                self._dead(f"[{dec.name}]: its subtasks' arguments depend on the open values "
                           f"({_agenda_text(found)} or {_agenda_text(subtasks)})")
                return None
        return found

    def _open(self, method: Method, dec: Decomposition, env: dict, args: tuple,
              bundle: Bundle) -> tuple[dict, Bundle] | None:
        """Bind the decomposition's open variables to tokens: each one's candidates are
        the values for which the precondition holds (in every state of the bundle); the
        bundle grows by every combination of them."""
        kinds = dict(dec.vars)
        opens = dec.open
        pools = [list(o.any_of) or self.problem.of_type(kinds[o.var]) for o in opens]
        kept = []
        for combo in itertools.product(*pools):
            self._tick()
            trial = {**env, **dict(zip((o.var for o in opens), combo, strict=True))}
            if dec.pre is None or all(dec.pre.fn(_env(trial, a), s.get) for s, a in bundle):
                kept.append(combo)
        if not kept:
            return None
        per_var = [tuple(dict.fromkeys(c[i] for c in kept)) for i in range(len(opens))]
        if len(kept) != len(list(itertools.product(*per_var))):
            return None  # not every combination of the candidates is capable
        where = f"{method.name}({', '.join(map(str, args))})[{dec.name}]"
        depth = len(bundle[0][1])
        tokens = [OpenValue(o.var, o.kind, per_var[i], o.query, f"{where}#{depth}")
                  for i, o in enumerate(opens)]
        env = {**env, **{o.var: tok for o, tok in zip(opens, tokens, strict=True)}}
        grown = tuple((state, assignment + tuple(zip(tokens, combo, strict=True)))
                      for state, assignment in bundle for combo in kept)
        return env, grown


def explore(problem: Problem, max_steps: int | None = None, max_nodes: int | None = None,
            worst: bool = False, merge: bool = True) -> Exploration:
    """The AND/OR graph of a conditional problem (one with ``agendas``)."""
    return Explorer(problem, max_steps, max_nodes, worst, merge).run()


def _resolve(args: tuple, assignment: Assignment) -> tuple:
    if not assignment:
        return args
    table = dict(assignment)
    return tuple(table.get(a, a) if isinstance(a, OpenValue) else a for a in args)


def _env(env: dict, assignment: Assignment) -> dict:
    if not assignment:
        return env
    table = dict(assignment)
    return {k: table.get(v, v) if isinstance(v, OpenValue) else v for k, v in env.items()}


def _number(value: Any, env: dict, get: Any) -> float:
    return float(value.fn(env, get)) if callable(value) else float(value)


def _agenda_text(agenda: Agenda) -> str:
    return ", ".join(f"{name}({', '.join(map(str, args))})" for name, args in agenda)


def _head(agenda: Agenda) -> str:
    name, args = agenda[0]
    return f"{name}({', '.join(map(str, args))})"


def _assigned(assignment: Assignment) -> str:
    return ", ".join(f"{token}={value}" for token, value in assignment)


def count_leaves(root: Turn | None, chosen: dict[int, int] | None = None) -> int:
    """Root-to-leaf paths (the DAG unfolded into HATP/EHDA's tree); with ``chosen`` (the
    policy's pick at each OR node), those of the policy only."""
    if root is None:
        return 0
    counts: dict[int, int] = {}

    def count(node: Turn) -> int:  # recursion as deep as a branch (max_steps)
        known = counts.get(id(node))
        if known is not None:
            return known
        if node.kind == LEAF_KIND:
            total = 1
        elif chosen is not None and node.kind == "or" and id(node) in chosen:
            total = count(node.children[chosen[id(node)]][1])
        else:
            total = 0
            for _, child in node.children:  # a loop, not sum(): no C frame per level
                total += count(child)
        counts[id(node)] = total
        return total

    with deep(MAX_STEPS):
        return count(root)

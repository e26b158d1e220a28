"""The search's action step, compiled once per action.

Applying an action is the search's inner loop (hundreds of thousands of times a
second): check the precondition, make the child state, run the effects, price
the action, and -- when a rule scores the plan's relations (crossed links,
waits, makespan) -- time it against the actions before it.  :class:`Stepper`
turns each action into one closure that does all of that with what it needs
already looked up: the effects as a flat tuple (``param.attr = <constant or
param>`` effects written by the step itself, from the argument tuple), the
cost and duration as a closure or a constant (cached by arguments with the
agent's rates when they read only static attributes), the variables bound by a
dict display (:func:`binder`).  The closures the expressions call back (the
state's ``get`` and ``put``) are made once per action, not per call: a step is
never re-entered, so one call's reads and writes live in containers cleared at
each call.  The state is read through its two dicts directly (one call per
read, not two), and the values the action reads are recorded only when a rule
needs them.

The relations are kept as the plan grows, in one small dict per state (under
:data:`TIMES_KEY`, copied from its parent's: one lookup a read, where entries
of the state itself would take two): for each value read or written,
``(entity, attribute)`` maps to who wrote it last (None: nobody yet), when
that action ends and when the last action that read it since ends; each
agent's name to when it is free; None to the makespan.  An action starts when the
writers of what it reads, the readers and the writer of what it writes, and
its agent's previous action are over.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from planner.evaluation.evaluate import Evaluator
from planner.model.domain import SOLE_AGENT, Action, ConditionalEffect, Problem
from planner.model.state import _FLAT as FLAT_BASE
from planner.model.state import FLAT, State

TIMES_KEY = (None, ("times",))
"""The state entry that times the plan so far (an attribute no domain has)."""
_NO_TIMES: dict = {}
_MISSING = object()

Step = Callable[[tuple, State, float], tuple | None]
"""``step(args, state, floor)``: None when the precondition is false, else the child
state, the action's variables, its cost, its duration, its agent and the new floor."""


class Stepper:
    """Compiles, once per action, the step the search applies it with."""

    def __init__(self, problem: Problem, evaluator: Evaluator):
        self.evaluator = evaluator
        self.links = evaluator.link_rates()
        """Crossed-links rules: their penalties are added to a partial plan's floor as
        its links appear."""
        self.waits = evaluator.wait_rates()
        """Timeout rules: their penalties are added as the waits appear."""
        self.duration_rate = evaluator.duration_rate
        self.timed = bool(self.links or self.waits or self.duration_rate)
        """Whether each action is timed as the plan grows."""
        self.dynamic = frozenset(a for t in problem.domain.types.values() for a in t.dynamic)
        """The attributes actions may change (the others need no timing entries)."""
        self.kinds = {e: problem.kind(e) for e in problem.entities}
        self.steps: dict[str, Step] = {}
        self._agents: dict[str, tuple] = {}

    def step(self, action: Action) -> Step:
        """The compiled step of ``action``."""
        step = self.steps.get(action.name)
        if step is None:
            step = self.steps[action.name] = self._compile(action)
        return step

    def agent(self, agent: str) -> tuple:
        """What an action by ``agent`` adds to the floor, looked up once per agent: the
        rate of its cost, each crossed-links rule's term for a link from another agent,
        and each timeout rule's (penalty, longest wait, rate)."""
        known = self._agents.get(agent)
        if known is None:
            kind = self.kinds.get(agent)
            known = self._agents[agent] = (
                self.evaluator.step_rate(kind),
                tuple(selected.penalty(agent, kind) * rate for selected, rate in self.links),
                tuple((selected.penalty(agent, kind), selected.rule.max_wait, rate)
                      for selected, rate in self.waits))
        return known

    def _compile(self, action: Action) -> Step:
        bind = binder(action.names)
        pre = action.pre.fn if action.pre is not None else None
        if any(isinstance(e, ConditionalEffect) for e in action.effects):
            apply: Callable | None = action.apply
            effects: tuple = ()
        else:
            apply, effects = None, tuple(e.fn for e in action.effects)
        plain = None
        """The effects as (argument written, attribute, argument assigned or None, constant,
        the effect) when all are ``param.attr = <constant or param>``."""
        if apply is None and all(e.plain is not None for e in action.effects):
            names = action.names
            plain = tuple(
                (names.index(var), attr, None if assigned is None else names.index(assigned),
                 value, e.fn)
                for e in action.effects
                for var, attr, assigned, value in (e.plain,))
        cost = action.cost.fn if callable(action.cost) else None
        cost_value = None if callable(action.cost) else action.cost
        duration = action.duration.fn if callable(action.duration) else None
        duration_value = None if callable(action.duration) else action.duration
        performer = action.agent
        rates = self.agent
        timed = self.timed
        dynamic = self.dynamic
        duration_rate = self.duration_rate
        missing = _MISSING
        flat, flat_size = FLAT_BASE, FLAT
        fixed: dict[tuple, tuple] | None = (
            {} if all(not callable(e) or not (e.reads & dynamic)
                      for e in (action.cost, action.duration)) else None)
        """Price, length, agent and the agent's rates by arguments, when the cost and the
        duration read only static attributes (the same in every state of the problem)."""
        # What one call reads and writes: the step is never re-entered, so these live
        # as long as the step (cleared per call) and the closures over them are made once.
        read: dict[tuple, Any] = {}
        written: list[tuple] = []
        source: dict = {}  # the state's own changes and its base, then the child's changes
        behind: dict = {}
        target: dict = {}
        setter: Callable = target.__setitem__

        def get(entity: str, attribute: Any) -> Any:
            key = (entity, attribute)
            value = source.get(key, missing)
            return behind.get(key) if value is missing else value

        def get_read(entity: str, attribute: Any) -> Any:
            key = (entity, attribute)
            if attribute in dynamic:  # a static value has no writer to wait for
                read[key] = None
            value = source.get(key, missing)
            return behind.get(key) if value is missing else value

        def put_written(entity: str, attribute: Any, value: Any) -> None:
            key = (entity, attribute)
            written.append(key)
            target[key] = value

        def set_written(entity: str, attribute: Any, value: Any) -> None:
            written.append((entity, attribute))
            setter(entity, attribute, value)

        def put(entity: str, attribute: Any, value: Any) -> None:
            target[(entity, attribute)] = value

        def step(args: tuple, state: State, floor: float) -> tuple | None:
            nonlocal source, behind, target, setter
            env = bind(args)
            source, behind = state.delta, state.base
            if not timed:
                if pre is not None and not pre(env, get):
                    return None
                child = state.child()
                if child.__class__ is State:
                    target = child.delta
                    writes = put
                else:
                    writes = child.set
                if apply is None:
                    for effect in effects:
                        effect(env, get, writes)
                else:
                    apply(env, get, writes)
                known = None if fixed is None else fixed.get(args)
                if known is None:
                    known = price_of(env, args)
                price, length, agent, rate, _, _ = known
                return child, env, price, length, agent, floor + price * rate
            # links and times need what the action reads and writes
            read.clear()
            if pre is not None and not pre(env, get_read):
                return None
            if behind is flat and state.__class__ is State and len(source) <= flat_size:
                target = dict(source)  # State.child() without the call, for a flat state
                child = State(flat, target)
            else:
                child = state.child()
                target = child.delta
            times = source.get(TIMES_KEY, missing)
            if times is missing:
                times = behind.get(TIMES_KEY, _NO_TIMES)
            tget = times.get
            written.clear()
            start = 0.0
            if plain is not None and child.__class__ is State:
                for owner, attr, assigned, value, effect in plain:  # effect(...) inlined
                    entity = args[owner]
                    if entity.__class__ is not str:
                        effect(env, get_read, put_written)  # raises: not an entity
                    key = (entity, attr)
                    written.append(key)
                    target[key] = value if assigned is None else args[assigned]
                    mark = tget(key)  # the last writer and readers of what it writes
                    if mark is not None:
                        if mark[1] > start:
                            start = mark[1]
                        if mark[2] > start:
                            start = mark[2]
            else:
                writes = put_written if child.__class__ is State else set_written
                if child.__class__ is not State:
                    setter = child.set
                if apply is None:
                    for effect in effects:
                        effect(env, get_read, writes)
                else:
                    apply(env, get_read, writes)
                for key in written:
                    mark = tget(key)
                    if mark is not None:
                        if mark[1] > start:
                            start = mark[1]
                        if mark[2] > start:
                            start = mark[2]
            known = None if fixed is None else fixed.get(args)
            if known is None:
                known = price_of(env, args)
            price, length, agent, rate, links, waits = known
            new = target[TIMES_KEY] = dict(times)  # State.set without the call
            added = 0.0
            for key in read:  # what it read, and now when (same keys: no resizing)
                mark = read[key] = tget(key)
                if mark is not None:
                    writer, written_at, _ = mark
                    if writer is not None and writer != agent:
                        for term in links:
                            added += term
                    if written_at > start:
                        start = written_at
            free = tget(agent)
            if free is not None:
                if free > start:
                    start = free
                for penalty, longest, wait_rate in waits:
                    gap = start - free
                    if gap > longest:
                        added += penalty * (gap - longest) * wait_rate
            end = start + length
            unread = (None, 0.0, end)
            for key, mark in read.items():
                if mark is None:
                    new[key] = unread
                elif mark[2] < end:
                    new[key] = (mark[0], mark[1], end)
            mark = (agent, end, 0.0)
            for key in written:  # after the reads: a write clears the readers
                new[key] = mark
            new[agent] = end
            makespan = tget(None) or 0.0
            if end > makespan:
                new[None] = end
                added += (end - makespan) * duration_rate
            return child, env, price, length, agent, floor + price * rate + added

        def price_of(env: dict, args: tuple) -> tuple:
            """Price, length, agent and the agent's rates (the state read is the parent's)."""
            price = cost_value if cost is None else cost(env, get)
            length = duration_value if duration is None else duration(env, get)
            agent = SOLE_AGENT if performer is None else env[performer]
            known = (price, length, agent, *rates(agent))
            if fixed is not None:
                fixed[args] = known
            return known

        return step

def binder(names: tuple[str, ...]) -> Callable[[tuple], dict[str, Any]]:
    """``bind(args)``: the variables of an action called with ``args`` (a ValueError when
    their numbers differ).  One dict display for the usual few parameters: four times
    faster than ``dict(zip(names, args, strict=True))``."""
    if len(names) == 1:
        (k0,) = names

        def bind1(args: tuple) -> dict[str, Any]:
            (a0,) = args
            return {k0: a0}

        return bind1
    if len(names) == 2:
        k0, k1 = names

        def bind2(args: tuple) -> dict[str, Any]:
            a0, a1 = args
            return {k0: a0, k1: a1}

        return bind2
    if len(names) == 3:
        k0, k1, k2 = names

        def bind3(args: tuple) -> dict[str, Any]:
            a0, a1, a2 = args
            return {k0: a0, k1: a1, k2: a2}

        return bind3
    if len(names) == 4:
        k0, k1, k2, k3 = names

        def bind4(args: tuple) -> dict[str, Any]:
            a0, a1, a2, a3 = args
            return {k0: a0, k1: a1, k2: a2, k3: a3}

        return bind4
    return lambda args: dict(zip(names, args, strict=True))

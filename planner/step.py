"""The search's action step, compiled once per action.

Applying an action is the search's inner loop (hundreds of thousands of times a
second): check the precondition, make the child state, run the effects, price
the action, and -- when a rule scores the plan's relations (crossed links,
waits, makespan) -- time it against the actions before it.  :class:`Stepper`
turns each action into one closure that does all of that with what it needs
already looked up: the effects as a flat tuple, the cost and duration as a
closure or a constant, the agent's rates by agent.  The state is read through
its two dicts directly (one call per read, not two), and the values the action
reads are recorded only when a rule needs them.

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

from planner.domain import SOLE_AGENT, Action, ConditionalEffect, Problem
from planner.evaluate import Evaluator
from planner.state import State

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
        names = action.names
        pre = action.pre.fn if action.pre is not None else None
        if any(isinstance(e, ConditionalEffect) for e in action.effects):
            apply: Callable | None = action.apply
            effects: tuple = ()
        else:
            apply, effects = None, tuple(e.fn for e in action.effects)
        cost = action.cost.fn if callable(action.cost) else None
        cost_value = None if callable(action.cost) else action.cost
        duration = action.duration.fn if callable(action.duration) else None
        duration_value = None if callable(action.duration) else action.duration
        performer = action.agent
        agents = self._agents
        rates = self.agent
        timed = self.timed
        dynamic = self.dynamic
        duration_rate = self.duration_rate
        missing = _MISSING

        def step(args: tuple, state: State, floor: float) -> tuple | None:
            env = dict(zip(names, args, strict=True))
            delta, base = state.delta, state.base
            if timed:  # links and times need what the action reads and writes
                read: dict[tuple, Any] = {}

                def get(entity: str, attribute: Any) -> Any:
                    key = (entity, attribute)
                    if attribute in dynamic:  # a static value has no writer to wait for
                        read[key] = None
                    value = delta.get(key, missing)
                    return base.get(key) if value is missing else value
            else:
                get = state.get
            if pre is not None and not pre(env, get):
                return None
            child = state.child()
            if timed:
                written: list[tuple] = []
                if child.__class__ is State:
                    cdelta = child.delta

                    def put(entity: str, attribute: Any, value: Any) -> None:
                        key = (entity, attribute)
                        written.append(key)
                        cdelta[key] = value
                else:
                    cset = child.set

                    def put(entity: str, attribute: Any, value: Any) -> None:
                        written.append((entity, attribute))
                        cset(entity, attribute, value)
            else:
                put = child.set
            if apply is None:
                for effect in effects:
                    effect(env, get, put)
            else:
                apply(env, get, put)
            get = state.get
            price = cost_value if cost is None else cost(env, get)
            length = duration_value if duration is None else duration(env, get)
            agent = SOLE_AGENT if performer is None else env[performer]
            rate, links, waits = agents.get(agent) or rates(agent)
            floor += price * rate
            if not timed:
                return child, env, price, length, agent, floor
            times = delta.get(TIMES_KEY, missing)
            if times is missing:
                times = base.get(TIMES_KEY, _NO_TIMES)
            new = dict(times)
            child.delta[TIMES_KEY] = new  # State.set without the call: no domain has it
            added = 0.0
            start = 0.0
            for key in read:  # what it read, and now when (same keys: no resizing)
                mark = read[key] = times.get(key)
                if mark is not None:
                    writer = mark[0]
                    if writer is not None and writer != agent:
                        for term in links:
                            added += term
                    if mark[1] > start:
                        start = mark[1]
            for key in written:
                mark = read[key] if key in read else times.get(key)
                if mark is not None:
                    if mark[1] > start:
                        start = mark[1]
                    if mark[2] > start:
                        start = mark[2]
            free = times.get(agent)
            if free is not None:
                if free > start:
                    start = free
                for penalty, longest, wait_rate in waits:
                    gap = start - free
                    if gap > longest:
                        added += penalty * (gap - longest) * wait_rate
            end = start + length
            for key, mark in read.items():
                if mark is None:
                    new[key] = (None, 0.0, end)
                elif mark[2] < end:
                    new[key] = (mark[0], mark[1], end)
            for key in written:  # after the reads: a write clears the readers
                new[key] = (agent, end, 0.0)
            new[agent] = end
            makespan = times.get(None) or 0.0
            if end > makespan:
                new[None] = end
                added += (end - makespan) * duration_rate
            return child, env, price, length, agent, floor + added

        return step

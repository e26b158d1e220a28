"""A running instance of a communication scheme.

An instance is small on purpose (a robot may run thousands of act x task
nodes): the name of its flat state in the shared ``transitions`` machine, two
event queues, its pending timers and whom to tell about what happens.  It
follows SCXML's run-to-completion rules: an event sent while an instance is
busy waits on the external queue; events raised inside a step go to the
internal queue, which is emptied, together with eventless transitions, before
the next outside event is looked at.
"""

from __future__ import annotations

import itertools
from collections import deque
from typing import TYPE_CHECKING, Any

from shary.clock import Clock, Timer
from shary.compiler import EVENTLESS
from shary.model import Cancel, Log, Raise, Send, State
from shary.statechart import ENTER, RAISE, Step

if TYPE_CHECKING:
    from shary.compiler import CompiledScheme

MAX_MICROSTEPS = 10_000
"""Microsteps allowed in one macrostep before the scheme is declared to be looping."""

_send_ids = itertools.count(1)


class Event:
    """An event as conditions and listeners see it: a name and optional data."""

    __slots__ = ("name", "data")

    def __init__(self, name: str, data: Any = None):
        self.name = name
        self.data = data

    def __repr__(self) -> str:
        return f"Event({self.name!r})" if self.data is None else \
            f"Event({self.name!r}, {self.data!r})"


class SchemeListener:
    """What an instance tells the outside world; override what you need.

    The act x task layer listens here: entering a state that carries an act
    launches that act's recipe, leaving it stops the recipe.
    """

    def entered(self, instance: SchemeInstance, state: State, event: Event | None) -> None:
        """``state`` was entered (before its ``on_entry`` actions run)."""

    def exited(self, instance: SchemeInstance, state: State, event: Event | None) -> None:
        """``state`` was left (after its ``on_exit`` actions ran)."""

    def logged(self, instance: SchemeInstance, text: str) -> None:
        """A ``log`` action ran."""

    def finished(self, instance: SchemeInstance, state: State) -> None:
        """A final state at the top of the scheme was entered; the instance is done."""


class LivelockError(RuntimeError):
    """A scheme kept taking eventless or raised transitions without ever settling."""


class SchemeInstance:
    """One running copy of a compiled scheme (start one with :meth:`CompiledScheme.start`)."""

    __slots__ = ("definition", "state", "clock", "listener", "context", "finished",
                 "_internal", "_external", "_busy", "_timers", "_frozen", "__weakref__")

    def __init__(self, definition: CompiledScheme, clock: Clock, listener: Any = None,
                 context: Any = None):
        self.definition = definition
        self.state = definition.initial_name
        self.clock = clock
        self.listener = listener
        self.context = context
        self.finished = False
        self._internal: deque[Event] = deque()
        self._external: deque[Event] = deque()
        self._busy = False
        self._timers: dict[str, Timer] | None = None
        self._frozen: dict[str, tuple[float, tuple]] | None = None

    # -- queries ---------------------------------------------------------

    @property
    def configuration(self) -> tuple[str, ...]:
        """Names of the active atomic states, in document order."""
        return self.definition.machine.states[self.state].leaves

    @property
    def active(self) -> frozenset[str]:
        """Names of every active state (atomic and their ancestors)."""
        return self.definition.machine.states[self.state].active_names

    def is_active(self, name: str) -> bool:
        return name in self.active

    # -- running ---------------------------------------------------------

    def freeze(self) -> None:
        """Stop the instance's clock: pending timeouts keep their remaining time.

        Used when a whole task is suspended by a more urgent one: its scheme
        must not give up on its partner while it is not even running.
        """
        if self._frozen is not None or not self._timers:
            self._frozen = self._frozen or {}
            return
        now = self.clock.now()
        self._frozen = {key: (max(0.0, t.due - now), t.args) for key, t in self._timers.items()}
        for timer in self._timers.values():
            timer.cancel()
        self._timers.clear()

    def thaw(self) -> None:
        """Restart the timeouts stopped by :meth:`freeze`, with their remaining time."""
        frozen, self._frozen = self._frozen or {}, None
        for key, (remaining, args) in frozen.items():
            self._start_timer(key, remaining, args[1])

    def start(self) -> None:
        """Enter the initial states and settle (called once by ``CompiledScheme.start``)."""
        self._busy = True
        try:
            self._play(self.definition.initial_step, self.definition.initial_name, None)
            self._settle()
            self._drain()
        finally:
            self._busy = False

    def send(self, name: str, data: Any = None) -> None:
        """Deliver an outside event and run to completion (queued if the instance is busy)."""
        event = Event(name, data)
        if self._busy:
            self._external.append(event)
            return
        self._busy = True
        try:
            self._macrostep(event)
            self._drain()
        finally:
            self._busy = False

    def _drain(self) -> None:
        external = self._external
        while external and not self.finished:
            self._macrostep(external.popleft())

    def _macrostep(self, event: Event) -> None:
        if self.finished:
            return
        events = self.definition.machine.events
        trigger = events.get(event.name) or self.definition.event(event.name)
        trigger.trigger(self, event)
        self._settle()

    def _settle(self) -> None:
        events = self.definition.machine.events
        eventless = (events.get(EVENTLESS) or self.definition.event(EVENTLESS)) \
            if self.definition.has_eventless else None
        internal = self._internal
        steps = 0
        while not self.finished:
            if eventless is not None and eventless.trigger(self, None):
                pass
            elif internal:
                event = internal.popleft()
                trigger = events.get(event.name) or self.definition.event(event.name)
                trigger.trigger(self, event)
            else:
                return
            steps += 1
            if steps > MAX_MICROSTEPS:
                raise LivelockError(f"scheme {self.definition.scheme.name!r} took more than "
                                    f"{MAX_MICROSTEPS} microsteps without settling")

    def _play(self, step: Step, target: str, event: Event | None) -> None:
        """Play one microstep computed by :mod:`shary.statechart` (called by the machine)."""
        timers = self.definition.timers
        listener = self.listener
        for state in step.exits:
            if self._timers and timers[state.name]:
                for name, _ in timers[state.name]:
                    pending = self._timers.pop(name, None)
                    if pending is not None:
                        pending.cancel()
            if state.on_exit:
                self._run(state.on_exit)
            if listener is not None:
                listener.exited(self, state, event)
        for transition in step.transitions:
            self._run(transition.actions)
        self.state = target
        for kind, item in step.entries:
            if kind is ENTER:
                if listener is not None:
                    listener.entered(self, item, event)
                if item.on_entry:
                    self._run(item.on_entry)
                for name, delay in timers[item.name]:
                    self._start_timer(name, delay, name)
            elif kind is RAISE:
                self._internal.append(Event(item))
            else:
                self.finished = True
                if self._timers:
                    for pending in self._timers.values():
                        pending.cancel()
                    self._timers.clear()
                if listener is not None:
                    listener.finished(self, item)

    def _start_timer(self, key: str, delay: float, event: str) -> None:
        if self._timers is None:
            self._timers = {}
        previous = self._timers.pop(key, None)
        if previous is not None:
            previous.cancel()
        self._timers[key] = self.clock.call_later(delay, self._fire, key, event)

    def _fire(self, key: str, event: str) -> None:
        if self._timers is not None:
            self._timers.pop(key, None)
        self.send(event)

    def _run(self, actions: tuple) -> None:
        for action in actions:
            if isinstance(action, Raise):
                self._internal.append(Event(action.event))
            elif isinstance(action, Send):
                if action.delay > 0:
                    key = action.id or f"send-{next(_send_ids)}"
                    self._start_timer(key, action.delay, action.event)
                else:
                    self._external.append(Event(action.event))
            elif isinstance(action, Cancel):
                pending = self._timers.pop(action.id, None) if self._timers else None
                if pending is not None:
                    pending.cancel()
            elif isinstance(action, Log) and self.listener is not None:
                self.listener.logged(self, action.text)

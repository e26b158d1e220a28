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
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from shary.statechart import datamodel
from shary.statechart.clock import Clock, Timer
from shary.statechart.datamodel import DataEvent
from shary.statechart.expressions import EvaluationError
from shary.statechart.model import PARENT, Cancel, Invoke, Log, Raise, Send, State
from shary.statechart.semantics import ACTIONS, DONE, ENTER, EVENTLESS, INVOKE, RAISE, Step
from userfiles.errors import Problem

if TYPE_CHECKING:
    from shary.statechart.compiler import CompiledScheme

MAX_MICROSTEPS = 1_000
"""Microsteps allowed in one macrostep before the scheme is declared to be looping."""
MAX_ECHOES = 1_000
"""Events an instance may send itself at one instant of its clock (zero-delay sends and
timers) with no outside event in between, before it is declared to be looping."""

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

    def invoking(self, instance: SchemeInstance, state: State, invoke: Invoke) -> Any:
        """The listener of the child scheme that ``state`` is about to invoke.

        None by default: the child runs silently, and its parent hears of it
        through ``done.invoke.ID.OUTCOME``.  Return ``self`` to hear the
        child's states too (``instance.parent`` and ``instance.invoke_id`` tell
        its calls from the parent's; note that ``finished`` then also comes for
        the child), or another listener.
        """
        return None


class LivelockError(RuntimeError):
    """A scheme kept running without ever settling or letting time pass.

    Either an unbounded run of internal events and eventless transitions in
    one macrostep, or events it sends itself (zero-delay sends or timers) at
    one instant, again and again.  ``problem`` places it at the transition
    that kept being taken, for ``FILE:LINE:COL: error: …``.
    """

    def __init__(self, message: str, problem: Problem):
        super().__init__(message)
        self.problem = problem


class SchemeInstance:
    """One running copy of a compiled scheme (start one with :meth:`CompiledScheme.start`)."""

    __slots__ = ("definition", "state", "clock", "listener", "context", "finished", "parent",
                 "invoke_id", "_internal", "_external", "_busy", "_timers", "_frozen",
                 "_to_invoke", "_invoked", "_echoes", "_echo_at", "_outbox", "data", "_live",
                 "__weakref__")

    def __init__(self, definition: CompiledScheme, clock: Clock, listener: Any = None,
                 context: Any = None):
        self.definition = definition
        self.state = definition.initial_name
        self.clock = clock
        self.listener = listener
        self.context = context
        self.finished = False
        self.parent: SchemeInstance | None = None
        """The instance that invoked this one (None at the top)."""
        self.invoke_id: str | None = None
        self._internal: deque[Event] = deque()
        self._external: deque[Event] = deque()
        self._busy = False
        self._timers: dict[str, Timer] | None = None
        self._frozen: dict[str, tuple[float, tuple]] | None = None
        self._to_invoke: list[State] | None = None
        self._invoked: dict[str, list[tuple[Invoke, SchemeInstance]]] | None = None
        self._echoes = 0
        self._echo_at = -1.0
        self._outbox: deque[Event] | None = None
        """Events for the parent, sent while it was idle: delivered when this step ends."""
        self.data: dict[str, Any] | None = None
        """The variables of a scheme with a data model (None without one)."""
        self._live: set[str] | None = None
        """During a microstep of a scheme with a data model, the states active at that
        moment, as ``In()`` must see them between one state's exit and another's entry."""

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
        """Whether ``name`` is active; in the middle of a microstep of a scheme with a data
        model, a state counts from just before its on_entry to just after its on_exit."""
        live = self._live
        return name in (live if live is not None else self.active)

    @property
    def invoke_path(self) -> str:
        """The invoke ids from the top instance down to this one, joined by ``/``."""
        ids = []
        node: SchemeInstance | None = self
        while node is not None and node.parent is not None:
            ids.append(node.invoke_id or "")
            node = node.parent
        return "/".join(reversed(ids))

    # -- running ---------------------------------------------------------

    def freeze(self) -> None:
        """Stop the instance's clock: pending timeouts keep their remaining time.

        Used when a whole task is suspended by a more urgent one: its scheme
        must not give up on its partner while it is not even running.  The
        children it invoked are frozen with it.
        """
        for child in self._children():
            child.freeze()
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
            self._start_timer(key, remaining, args[1], args[2])
        for child in self._children():
            child.thaw()

    def _children(self) -> list[SchemeInstance]:
        """The invoked children still running."""
        return [c for kids in (self._invoked or {}).values() for _, c in kids if not c.finished]

    def start(self, given: dict[str, Any] | None = None) -> None:
        """Enter the initial states and settle (called once by ``CompiledScheme.start``).

        ``given`` are the values an invoking parent passes to variables of the
        data model, if the scheme has one.
        """
        scheme = self.definition.scheme
        if scheme.datamodel is not None:
            for why in datamodel.start(self, scheme, given):
                self._internal.append(datamodel.error_event(why))
        self._complete(lambda: self._play(self.definition.initial_step,
                                          self.definition.initial_name, None))

    def _complete(self, begin: Callable[[], None]) -> None:
        """Run ``begin`` and everything it leads to, as one busy step of this instance.

        Then settle, start the invokes, take the queued outside events, and
        hand the parent what was kept for it (:meth:`_post`).
        """
        self._busy = True
        try:
            begin()
            self._settle()
            if self._to_invoke:
                self._start_invokes()
            self._drain()
        finally:
            self._busy = False
        if self._outbox:
            self._flush()

    def send(self, name: str, data: Any = None, *, event: Any = None) -> None:
        """Deliver an outside event and run to completion (queued if the instance is busy).

        ``event`` is an event made elsewhere (one with SCXML's fields, from
        another scheme), to be delivered as it is.
        """
        if event is None:
            event = Event(name, data)
        self._echoes = 0
        if self._busy:
            self._external.append(event)
            return
        self._busy = True
        try:
            self._macrostep(event)
            self._drain()
        finally:
            self._busy = False
        if self._outbox:
            self._flush()

    def _drain(self) -> None:
        external = self._external
        while external and not self.finished:
            self._macrostep(external.popleft())

    def _macrostep(self, event: Event) -> None:
        if self.finished:
            return
        if self._invoked:
            self._forward(event)
        if self.data is not None:
            datamodel.take(self, event, "external")
        events = self.definition.machine.events
        trigger = events.get(event.name) or self.definition.event(event.name)
        trigger.trigger(self, event)
        self._settle()
        if self._to_invoke:
            self._start_invokes()

    def _settle(self) -> None:
        events = self.definition.machine.events
        eventless = (events.get(EVENTLESS) or self.definition.event(EVENTLESS)) \
            if self.definition.has_eventless else None
        internal = self._internal
        steps = 0
        while not self.finished:
            if eventless is not None and eventless.trigger(self, None):
                name = None
            elif internal:
                event = internal.popleft()
                name = event.name
                if self.data is not None:
                    datamodel.take(self, event, "internal")
                trigger = events.get(name) or self.definition.event(name)
                trigger.trigger(self, event)
            else:
                return
            steps += 1
            if steps > MAX_MICROSTEPS:
                self._livelock(name, f"more than {MAX_MICROSTEPS} microsteps in one macrostep "
                               "without settling (an endless run of raised events or eventless "
                               "transitions)")

    def _livelock(self, event: str | None, why: str) -> None:
        """Stop the instance and raise :class:`LivelockError` at the looping transition."""
        self._stop()
        scheme = self.definition.scheme
        snapshot = self.definition.machine.states[self.state].snapshot
        chains = self.definition.semantics.candidates(snapshot, event)
        where = chains[0][0].mark if chains else scheme.root.mark
        trigger = "eventless transitions" if event is None else f"event {event!r}"
        message = f"livelock in scheme {scheme.name!r}: {why}; it kept taking {trigger}, " \
                  f"last in {', '.join(self.configuration) or 'no state'}"
        raise LivelockError(message, Problem(scheme.file, *where, message))

    def _send_self(self, event: Any, data: Any = None) -> None:
        """Send an event the instance gives itself (a timer, a child's end): counted.

        ``event`` is a name, or an event with SCXML's fields from the data model.
        """
        name = event if isinstance(event, str) else event.name
        self._echo(name)
        count = self._echoes
        if isinstance(event, str):  # which resets the count, as an outside event does
            self.send(name, data)
        else:
            self.send(name, event=event)
        self._echoes = max(self._echoes, count)

    def _echo(self, event: str) -> None:
        """Count an event the instance gives itself; too many at one instant is a loop."""
        now = self.clock.now()
        if now != self._echo_at:
            self._echo_at, self._echoes = now, 0
        self._echoes += 1
        if self._echoes > MAX_ECHOES:
            self._livelock(event, f"it sent itself more than {MAX_ECHOES} events at {now:g} s "
                           "without time passing (a zero-delay loop of sends, timers or "
                           "invokes)")

    def _play(self, step: Step, target: str, event: Event | None) -> None:
        """Play one microstep computed by :mod:`shary.statechart.semantics` (called by the
        machine)."""
        timers = self.definition.timers
        listener = self.listener
        live = None
        if self.data is not None:  # the states active before the step (none at the start)
            exited = {s.name for s in step.exits}
            live = self._live = set(self.active).difference(
                item.name for kind, item in step.entries
                if kind is ENTER and item.name not in exited)
        for state in step.exits:
            if state.invokes and self._to_invoke and state in self._to_invoke:
                self._to_invoke.remove(state)  # left in the macrostep that entered it
            if self._timers and timers[state.name]:
                for name, _ in timers[state.name]:
                    pending = self._timers.pop(name, None)
                    if pending is not None:
                        pending.cancel()
            if state.on_exit:
                self._run(state.on_exit)
            if live is not None:
                live.discard(state.name)
            if state.invokes and self._invoked and state.name in self._invoked:
                for _, child in self._invoked.pop(state.name):
                    child.cancel()
            if listener is not None:
                listener.exited(self, state, event)
        for transition in step.transitions:
            self._run(transition.actions)
        self.state = target
        for kind, item in step.entries:
            if kind is ENTER:
                if live is not None:
                    live.add(item.name)
                    if item.name in self.definition.late:
                        datamodel.bind_late(self, item.name, self.definition.late[item.name])
                if listener is not None:
                    listener.entered(self, item, event)
                if item.on_entry:
                    self._run(item.on_entry)
                for name, delay in timers[item.name]:
                    self._start_timer(name, delay, name)
            elif kind is RAISE:
                self._internal.append(Event(item))
            elif kind is DONE:
                name, final = item
                self._internal.append(DataEvent(name, datamodel.done_data(self, final.donedata),
                                                type="internal"))
            elif kind is ACTIONS:
                self._run(item)
            elif kind is INVOKE:
                if self._to_invoke is None:
                    self._to_invoke = []
                self._to_invoke.append(item)
            else:
                if item.on_exit:  # SCXML leaves the final configuration when it ends
                    self._run(item.on_exit)
                self._stop()
                if listener is not None:
                    listener.finished(self, item)
                if self.parent is not None:
                    self.parent._child_finished(self, item)
        if live is not None:
            self._live = None

    def _stop(self) -> None:
        """Finish: no more events, timers cancelled, invoked children cancelled."""
        self.finished = True
        self._to_invoke = None
        if self._timers:
            for pending in self._timers.values():
                pending.cancel()
            self._timers.clear()
        invoked, self._invoked = self._invoked, None
        for children in (invoked or {}).values():
            for _, child in children:
                child.cancel()

    # -- invoked schemes -------------------------------------------------

    def _start_invokes(self) -> None:
        """Start the invokes of the states entered and not left in this macrostep.

        SCXML starts them at the end of the macrostep, in entry order, so a
        state passed through on the way somewhere else invokes nothing.
        """
        pending, self._to_invoke = self._to_invoke or [], None
        compiled = self.definition
        for state in pending:
            for invoke in state.invokes:
                given = datamodel.invoke_values(self, invoke) if self.data is not None \
                    else None
                if given is False:
                    continue
                child_def = compiled.child(invoke)
                hook = getattr(self.listener, "invoking", None)
                listener = hook(self, state, invoke) if hook is not None else None
                child = SchemeInstance(child_def, self.clock, listener, self.context)
                child.parent = self
                child.invoke_id = invoke.id
                if self._invoked is None:
                    self._invoked = {}
                self._invoked.setdefault(state.name, []).append((invoke, child))
                child.start(given)

    def _forward(self, event: Event) -> None:
        """Pass an outside event on to the children invoked with ``autoforward``."""
        if "@" in event.name:  # the parent's own timeouts are no outside events
            return
        for children in list(self._invoked.values()):
            for invoke, child in children:
                if invoke.autoforward and not child.finished:
                    child.send(event.name, event=event)

    def _child_finished(self, child: SchemeInstance, state: State) -> None:
        """An invoked child reached a final state at its top: ``done.invoke.ID.OUTCOME``."""
        for name, children in list((self._invoked or {}).items()):
            kept = [(i, c) for i, c in children if c is not child]
            if len(kept) != len(children):
                if kept:
                    self._invoked[name] = kept  # type: ignore[index]
                else:
                    del self._invoked[name]  # type: ignore[union-attr]
                name = f"done.invoke.{child.invoke_id}.{state.outcome}"
                if child.data is None and self.data is None:
                    child._post(Event(name, {"invoke": child.invoke_id, "outcome": state.outcome,
                                             "state": state.name}))
                else:
                    data = datamodel.done_data(child, state.donedata) if child.data is not None \
                        else None
                    child._post(DataEvent(name, data, invokeid=child.invoke_id))
                return

    def _to_parent(self, event: Event) -> None:
        """A send ``to: parent``: the invoking instance's external queue.

        A child that was cancelled (its invoking state left) is never heard
        from again, not even from the ``on_exit`` actions its cancelling runs;
        at the top, with no parent, the send fails as SCXML's does, with
        ``error.communication`` on the internal queue.
        """
        parent = self.parent
        if parent is None:
            self._internal.append(Event("error.communication", {"to": PARENT}))
        elif not parent.finished and any(c is self for kids in (parent._invoked or {}).values()
                                         for _, c in kids):
            self._post(event)

    def _post(self, event: Event) -> None:
        """Queue an event for the parent, or keep it until this step ends if the parent is idle.

        Keeping it means the parent never runs in the middle of one of its
        child's steps (which could cancel the child half-way), and events
        reach it in the order they were sent, ``done.invoke`` last.
        """
        parent = self.parent
        assert parent is not None
        if parent._busy:
            parent._echo(event.name)
            parent._external.append(event)
            return
        if self._outbox is None:
            self._outbox = deque()
        self._outbox.append(event)

    def _flush(self) -> None:
        """Deliver the events kept for the parent (see :meth:`_post`)."""
        outbox, parent = self._outbox, self.parent
        while outbox and parent is not None and not parent.finished:
            parent._send_self(outbox.popleft())
        self._outbox = None

    def _to_child(self, ident: str, event: Event) -> None:
        """A send ``to: ID``: the running child of that invoke id, or ``error.communication``."""
        for children in (self._invoked or {}).values():
            for invoke, child in children:
                if invoke.id == ident and not child.finished:
                    child.send(event.name, event=event)
                    return
        self._internal.append(Event("error.communication", {"to": ident}))

    def cancel(self) -> None:
        """Stop an invoked child because its invoking state was left.

        As SCXML says of a cancelled session, the on_exit actions of its
        active states run (innermost first) and its listener hears of each
        exit, so the acts it carried out are stopped; nothing it does from
        then on reaches its parent.
        """
        if self.finished:
            return
        self._stop()
        self._outbox = None
        snapshot = self.definition.machine.states[self.state].snapshot
        for state in sorted(snapshot.active, key=lambda s: s.order, reverse=True):
            if state.on_exit:
                self._run(state.on_exit)
            if self.listener is not None:
                self.listener.exited(self, state, None)
        self._internal.clear()
        self._external.clear()

    def _start_timer(self, key: str, delay: float, event: Any, to: str | None = None) -> None:
        if self._timers is None:
            self._timers = {}
        previous = self._timers.pop(key, None)
        if previous is not None:
            previous.cancel()
        self._timers[key] = self.clock.call_later(delay, self._fire, key, event, to)

    def _fire(self, key: str, event: Any, to: str | None) -> None:
        if self._timers is not None:
            self._timers.pop(key, None)
        if to is None:
            self._send_self(event)
            return
        made = Event(event) if isinstance(event, str) else event
        if self._busy:
            self._deliver(to, made)
        else:  # a step of this instance: it may raise error.communication
            self._complete(lambda: self._deliver(to, made))

    def _deliver(self, to: str, event: Event) -> None:
        if to == PARENT:
            self._to_parent(event)
        else:
            self._to_child(to, event)

    def _dispatch(self, event: Any, delay: float, ident: str | None, to: str | None) -> None:
        """Send an event made by the data model: after ``delay``, to ``to`` or to itself."""
        if delay > 0:
            self._start_timer(ident or f"send-{next(_send_ids)}", delay, event, to)
        elif to is not None:
            self._deliver(to, event)
        else:
            self._echo(event.name)
            self._external.append(event)

    def _cancel_send(self, ident: str) -> None:
        pending = self._timers.pop(ident, None) if self._timers else None
        if pending is not None:
            pending.cancel()

    def _run(self, actions: tuple) -> bool:
        """Run actions in order; False when one failed (``error.execution`` is then queued)."""
        for action in actions:
            if isinstance(action, Raise):
                self._internal.append(Event(action.event) if self.data is None else
                                      DataEvent(action.event, type="internal"))
            elif isinstance(action, Send) and action.computed is None and self.data is None:
                if action.delay > 0:
                    key = action.id or f"send-{next(_send_ids)}"
                    self._start_timer(key, action.delay, action.event, action.to)
                elif action.to is not None:
                    self._deliver(action.to, Event(action.event))
                else:
                    self._echo(action.event)
                    self._external.append(Event(action.event))
            elif isinstance(action, Cancel):
                self._cancel_send(action.id)
            elif isinstance(action, Log) and action.expr is None:
                if self.listener is not None:
                    self.listener.logged(self, action.text)
            else:
                try:
                    datamodel.execute(self, action)
                except EvaluationError as err:
                    if not isinstance(err, datamodel.Stopped):
                        self._internal.append(datamodel.error_event(str(err)))
                    return False
        return True

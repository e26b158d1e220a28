"""Compiling a scheme onto ``transitions``: one machine per scheme, shared by all instances.

``transitions``' HierarchicalMachine walks the state tree on every event, has
no history, times out with one thread per state, and resolves parallel regions
its own way rather than SCXML's.  Rather than change its meaning, we keep
``transitions``' core and feed it a flat machine:

* each state of the flat :class:`SchemeMachine` is a :class:`ConfigurationState`,
  one reachable :class:`~shary.statechart.semantics.Snapshot` of the scheme (its active
  states and recorded history), added when first reached;
* each event is a :class:`SchemeEvent`; the first time it meets a flat state it
  compiles, with :mod:`shary.statechart.semantics`, a :class:`StepTransition` holding the
  candidate transitions and the guards they depend on;
* a :class:`StepTransition` evaluates those guards, looks the microstep up
  (computed once per truth assignment) and hands it to the instance to play.

Instances are not ``transitions`` models added with ``add_model`` (that costs
tens of kilobytes and a tenth of a millisecond each): they only carry the
name of their flat state in ``state``, which is all ``Event.trigger`` needs.
Timeouts (``after 10s``) are timers on the instance's clock, not threads.
"""

from __future__ import annotations

from typing import Any

from transitions import Event, Machine
from transitions import State as FlatState
from transitions import Transition as FlatTransition

from shary.statechart import datamodel
from shary.statechart.clock import Clock, SimulatedClock
from shary.statechart.conditions import ConditionRegistry
from shary.statechart.instance import SchemeInstance
from shary.statechart.model import (
    EXPR_GUARD,
    IN_STATE,
    Invoke,
    Scheme,
    Transition,
    descriptor_matches,
)
from shary.statechart.semantics import EVENTLESS, Semantics, Snapshot, Step


class ConfigurationState(FlatState):
    """A flat state: one snapshot (active states and history) of the scheme."""

    def __init__(self, name: str, snapshot: Snapshot):
        super().__init__(name)
        self.snapshot = snapshot
        self.leaves = tuple(s.name for s in snapshot.leaves())
        self.active_names = frozenset(s.name for s in snapshot.active)
        self.finished = snapshot.finished


class StepTransition(FlatTransition):
    """All of a scheme's transitions that one event may take from one flat state.

    The guards it depends on are evaluated together; the resulting microstep is
    computed once per truth assignment and cached here.
    """

    def __init__(self, compiled: CompiledScheme, source: ConfigurationState,
                 candidates: list[list[Transition]]):
        super().__init__(source.name, None)
        self.compiled = compiled
        self.snapshot = source.snapshot
        self.candidates = candidates
        names = []
        for chain in candidates:
            for t in chain:
                if t.condition is not None and t.condition not in names:
                    names.append(t.condition)
        self.condition_names = tuple(names)
        self.condition_funcs = tuple(compiled.condition(n) for n in names)
        self.steps: dict[tuple[bool | None, ...], tuple[Step, str] | None] = {}
        self.lazy = compiled.scheme.datamodel is not None and bool(names)
        """Guards over data are evaluated as SCXML does, in document order and only until
        one transition of each chain is enabled: a failing one raises ``error.execution``."""
        self.by_name = dict(zip(names, self.condition_funcs, strict=True))

    def fire(self, instance: Any, event: Any) -> bool:
        """Take the microstep the guards select, if any (called by :meth:`SchemeEvent.trigger`)."""
        funcs = self.condition_funcs
        if self.lazy:
            key = self._lazy_key(instance, event)
        else:
            key = tuple(bool(f(instance, event)) for f in funcs) if funcs else ()
        try:
            step = self.steps[key]
        except KeyError:
            step = self.steps[key] = self._compile(key)
        if step is None:
            return False
        instance._play(step[0], step[1], event)
        return True

    def _lazy_key(self, instance: Any, event: Any) -> tuple[bool | None, ...]:
        """The truth of the guards a lazy selection reads (None for those it never reads)."""
        truth: dict[str, bool] = {}
        funcs = self.by_name
        for chain in self.candidates:
            for t in chain:
                name = t.condition
                if name is None:
                    break
                value = truth.get(name)
                if value is None:
                    value = truth[name] = bool(funcs[name](instance, event))
                if value != t.negated:
                    break
        return tuple(truth.get(n) for n in self.condition_names)

    def _compile(self, key: tuple[bool | None, ...]) -> tuple[Step, str] | None:
        semantics = self.compiled.semantics
        enabled = semantics.select(self.snapshot, self.candidates,
                                   dict(zip(self.condition_names, key, strict=True)))
        if not enabled:
            return None
        step = semantics.microstep(self.snapshot, enabled)
        return step, self.compiled.flat_state(step.target).name


class SchemeEvent(Event):
    """An event of the flat machine that compiles its transitions on first use.

    ``trigger`` does what ``Event._trigger`` does for one model, without its
    ``EventData``, model lookup and (empty) callback lists, and without the
    machine's ``_process`` queue: schemes keep their own run-to-completion
    queues (:mod:`shary.statechart.instance`), and this runs once per event of every
    live task.
    """

    def trigger(self, model: Any, event: Any) -> bool:  # type: ignore[override]
        name = model.state
        state = self.machine.states[name]
        if state.finished:
            return False
        transitions = self.transitions.get(name)
        if transitions is None:
            self.machine.compiled.compile_transition(self, state)
            transitions = self.transitions[name]
        for transition in transitions:
            if transition.fire(model, event):
                return True
        return False


class SchemeMachine(Machine):
    """The flat ``transitions`` machine of one compiled scheme (no models of its own)."""

    event_cls = SchemeEvent
    state_cls = ConfigurationState

    def __init__(self, compiled: CompiledScheme):
        super().__init__(model=None, states=[], initial=None, auto_transitions=False,
                         ignore_invalid_triggers=True, name=compiled.scheme.name)
        self.compiled = compiled


class CompiledScheme:
    """One scheme compiled for execution, shared by all its running instances."""

    def __init__(self, scheme: Scheme, conditions: ConditionRegistry | None = None):
        self.scheme = scheme
        self.conditions = conditions or ConditionRegistry()
        self.expressions = {t.guard: t.cond for s in scheme.states.values()
                            for t in s.transitions if t.cond is not None}
        missing = sorted({t.condition for s in scheme.states.values() for t in s.transitions
                          if t.condition is not None and t.in_state is None
                          and t.cond is None and t.condition not in self.conditions})
        if missing:
            raise KeyError(f"scheme {scheme.name!r} uses conditions that are not registered: "
                           f"{', '.join(missing)}")
        self.semantics = Semantics(scheme)
        self.machine = SchemeMachine(self)
        self._flat: dict[Snapshot, ConfigurationState] = {}
        step = self.semantics.initial_step()
        self.initial_step = step
        self.initial_name = self.flat_state(step.target).name
        self.clock: Clock = SimulatedClock()
        self.has_eventless = any(t.events is None for s in scheme.states.values()
                                 for t in s.transitions)
        self.timers: dict[str, tuple[tuple[str, float], ...]] = {
            s.name: tuple((t.events[0], t.after) for t in s.transitions
                          if t.after is not None and t.events)
            for s in scheme.states.values()}
        self.late: dict[str, tuple] = {}
        """A late-binding scheme's variables by the state that declares them."""
        if scheme.datamodel is not None and scheme.datamodel.late:
            for variable in scheme.datamodel.variables:
                if variable.state is not None:
                    self.late[variable.state] = self.late.get(variable.state, ()) + (variable,)
        self._children: dict[int, CompiledScheme] = {}
        self._descriptors: list[str] | None = None

    def child(self, invoke: Invoke) -> CompiledScheme:
        """The compiled child scheme of an invoke (compiled once, on first use)."""
        found = self._children.get(id(invoke.scheme))
        if found is None:
            found = self._children[id(invoke.scheme)] = CompiledScheme(invoke.scheme,
                                                                       self.conditions)
        return found

    def descriptors(self) -> list[str]:
        """Every event descriptor a transition of the scheme names, in document order.

        Timeouts are left out (they are the instance's own events).  Children
        invoked with ``autoforward`` count: what they take reaches them through
        this scheme.  This is what an event sent from outside is checked against.
        """
        if self._descriptors is None:
            out: dict[str, None] = {}
            for state in self.scheme.all_states():
                for t in state.transitions:
                    if t.after is None and t.events is not None:
                        out.update(dict.fromkeys(t.events))
                for invoke in state.invokes:
                    if invoke.autoforward:
                        out.update(dict.fromkeys(self.child(invoke).descriptors()))
            self._descriptors = list(out)
        return self._descriptors

    def can_take(self, event: str) -> bool:
        """Whether some state of the scheme (or an autoforwarded child) has a transition on it."""
        return any(descriptor_matches(d, event) for d in self.descriptors())

    def condition(self, name: str) -> Any:
        """The function of a guard's condition: registered, or ``in STATE``."""
        if name.startswith(IN_STATE):
            state = name[len(IN_STATE):]
            return lambda instance, event: state in instance.active
        if name.startswith(EXPR_GUARD):
            return datamodel.guard(self.expressions[name])
        return self.conditions[name]

    def flat_state(self, snapshot: Snapshot) -> ConfigurationState:
        """The flat state of a snapshot, added to the machine the first time it is reached."""
        found = self._flat.get(snapshot)
        if found is None:
            found = ConfigurationState(f"c{len(self._flat)}", snapshot)
            self._flat[snapshot] = found
            self.machine.add_state(found)
        return found

    def compile_transition(self, event: SchemeEvent, state: ConfigurationState) -> None:
        name = None if event.name == EVENTLESS else event.name
        candidates = self.semantics.candidates(state.snapshot, name)
        if candidates:
            event.add_transition(StepTransition(self, state, candidates))
        else:
            event.transitions[state.name] = []

    def expects(self, flat_state: str, event: str) -> bool:
        """Whether some active state of that flat state has a transition on ``event``.

        These are SHARY's expected acts: the monitors of the current scheme state.
        """
        transitions = self.event(event).transitions
        state = self.machine.states[flat_state]
        if state.name not in transitions:
            self.compile_transition(self.event(event), state)
        return bool(transitions[state.name])

    def event(self, name: str) -> SchemeEvent:
        """The flat machine's event of that name (created on first use)."""
        found = self.machine.events.get(name)
        if found is None:
            found = self.machine.events[name] = SchemeEvent(name, self.machine)
        return found

    def start(self, *, clock: Clock | None = None, listener: Any = None,
              context: Any = None) -> Any:
        """A new running instance of the scheme, entered into its initial states."""
        instance = SchemeInstance(self, clock or self.clock, listener, context)
        instance.start()
        return instance

    @property
    def flat_states(self) -> int:
        """How many snapshots have been reached so far (for diagnostics)."""
        return len(self._flat)


def compile_scheme(scheme: Scheme, conditions: ConditionRegistry | None = None) -> CompiledScheme:
    """Compile ``scheme`` once; start instances with :meth:`CompiledScheme.start`."""
    return CompiledScheme(scheme, conditions)


__all__ = ["CompiledScheme", "compile_scheme"]

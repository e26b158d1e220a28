"""SCXML's step semantics, computed ahead of time on a scheme model.

This module is the W3C SCXML algorithm (selection of enabled transitions in
document order, removal of conflicting transitions between parallel regions,
exit and entry sets, history recording, ``done.state.*`` events), written as
pure functions of a :class:`Snapshot`: the set of active states plus the
recorded history.  Because a data-model-free scheme's next snapshot depends
only on the snapshot, the event name and the truth of the guards involved, a
step is computed once and then replayed by every instance of the scheme: this
is what :mod:`shary.statechart.compiler` caches.

Registered conditions are evaluated all at once before selection (rather than
lazily, as SCXML does); with side-effect-free conditions, which is what
conditions must be, the result is the same.  Guards over a data model are
evaluated lazily, in document order, since one that fails raises
``error.execution`` (:class:`~shary.statechart.compiler.StepTransition`): the
selection reads only the guards evaluated, so the same steps serve both.
"""

from __future__ import annotations

from dataclasses import dataclass

from shary.statechart.model import COMPOUND, FINAL, HISTORY, PARALLEL, Scheme, State, Transition

EVENTLESS = "<eventless>"
"""Name of the event under which a compiled scheme looks for eventless transitions."""

ENTER, ACTIONS, INVOKE, RAISE, DONE, FINISH = "enter", "actions", "invoke", "raise", "done", \
    "finish"
"""Kinds of a step's entries: a state entered, default-entry content to run, a state
whose invokes start at the end of the macrostep, an internal event, a ``done.state`` event
whose data the final state computes, the end of the run."""


@dataclass(frozen=True)
class Snapshot:
    """Active states and recorded history: everything a step depends on."""

    active: frozenset[State]
    history: frozenset[tuple[State, frozenset[State]]] = frozenset()

    def leaves(self) -> list[State]:
        """Active atomic states, in document order."""
        return sorted((s for s in self.active if s.is_atomic), key=_order)

    @property
    def finished(self) -> bool:
        """True once a final state at the top of the scheme is active."""
        return any(s.kind == FINAL and s.parent is not None and s.parent.parent is None
                   for s in self.active)


@dataclass(frozen=True)
class Step:
    """One microstep: states left, transition content run, states entered, events raised."""

    exits: tuple[State, ...]
    transitions: tuple[Transition, ...]
    entries: tuple[tuple[str, object], ...]
    target: Snapshot


def _order(state: State) -> int:
    return state.order


class Semantics:
    """The SCXML algorithm over one scheme (see the module's docstring)."""

    def __init__(self, scheme: Scheme):
        self.scheme = scheme
        self.root = scheme.root
        self.by_name = scheme.states

    # -- selection -------------------------------------------------------

    def candidates(self, snapshot: Snapshot, event: str | None) -> list[list[Transition]]:
        """For each active atomic state, the transitions matching ``event``, in priority order."""
        out = []
        for leaf in snapshot.leaves():
            chain = []
            for state in [leaf, *leaf.ancestors()]:
                chain.extend(t for t in state.transitions if t.matches(event))
            if chain:
                out.append(chain)
        return out

    def select(self, snapshot: Snapshot, candidates: list[list[Transition]],
               truth: dict[str, bool]) -> list[Transition]:
        """Enabled transitions given the truth of each condition, conflicts removed."""
        enabled: list[Transition] = []
        for chain in candidates:
            for t in chain:
                if t.guard is None or truth[t.condition] != t.negated:
                    if t not in enabled:
                        enabled.append(t)
                    break
        return self._remove_conflicts(snapshot, enabled)

    def _remove_conflicts(self, snapshot: Snapshot, enabled: list[Transition]) -> list[Transition]:
        history = dict(snapshot.history)
        filtered: list[Transition] = []
        for t1 in enabled:
            preempted = False
            to_remove = []
            exit1 = self.exit_set(snapshot.active, [t1], history)
            for t2 in filtered:
                if exit1 & self.exit_set(snapshot.active, [t2], history):
                    if t1.source.is_descendant_of(t2.source):
                        to_remove.append(t2)
                    else:
                        preempted = True
                        break
            if not preempted:
                filtered = [t for t in filtered if t not in to_remove]
                filtered.append(t1)
        return filtered

    # -- exit and entry sets --------------------------------------------

    def targets(self, t: Transition) -> list[State]:
        return [self.by_name[n] for n in t.targets]

    def history_default(self, h: State) -> list[State]:
        """Where a history state leads when its parent was never left."""
        if h.default:
            return [self.by_name[n] for n in h.default]
        parent = h.parent
        assert parent is not None
        if parent.kind == PARALLEL:
            return parent.proper_children()
        return [self.by_name[n] for n in parent.initial]

    def effective_targets(self, t: Transition, history: dict) -> list[State]:
        out: list[State] = []
        for s in self.targets(t):
            if s.kind == HISTORY:
                found = history.get(s)
                for x in (sorted(found, key=_order) if found is not None
                          else self.history_default(s)):
                    if x not in out:
                        out.append(x)
            elif s not in out:
                out.append(s)
        return out

    def domain(self, t: Transition, history: dict) -> State | None:
        targets = self.effective_targets(t, history)
        if not targets:
            return None
        if t.internal and t.source.is_compound and all(s.is_descendant_of(t.source)
                                                       for s in targets):
            return t.source
        return self.lcca([t.source, *targets])

    def lcca(self, states: list[State]) -> State:
        """Least common compound ancestor (the root counts as compound)."""
        for anc in states[0].ancestors():
            if anc.kind == COMPOUND and all(s.is_descendant_of(anc) for s in states[1:]):
                return anc
        return self.root

    def exit_set(self, active: frozenset[State] | set[State], transitions: list[Transition],
                 history: dict) -> set[State]:
        out: set[State] = set()
        for t in transitions:
            if t.targets:
                domain = self.domain(t, history)
                if domain is not None:
                    out.update(s for s in active if s.is_descendant_of(domain))
        return out

    def entry_set(self, transitions: list[Transition], history: dict
                  ) -> tuple[dict[State, None], dict[State, tuple]]:
        """States to enter, and the default-entry content to run after each one's on_entry.

        The content is SCXML's ``defaultEntryContent`` (the actions of an
        ``initial`` transition, for a compound state entered by default) and
        ``defaultHistoryContent`` (of a history's default transition, run
        after its parent's on_entry when there is no history yet).
        """
        to_enter: dict[State, None] = {}
        content: dict[State, tuple] = {}
        for t in transitions:
            for s in self.targets(t):
                self._add_descendants(s, to_enter, history, content)
            ancestor = self.domain(t, history)
            for s in self.effective_targets(t, history):
                self._add_ancestors(s, ancestor, to_enter, history, content)
        return to_enter, content

    def _add_descendants(self, state: State, to_enter: dict, history: dict,
                         content: dict) -> None:
        if state.kind == HISTORY:
            parent = state.parent
            assert parent is not None
            found = history.get(state)
            if found is None and state.initial_actions:  # after the initial transition's
                content[parent] = content.get(parent, ()) + state.initial_actions
            restored = sorted(found, key=_order) if found is not None \
                else self.history_default(state)
            for s in restored:
                self._add_descendants(s, to_enter, history, content)
            for s in restored:
                self._add_ancestors(s, parent, to_enter, history, content)
            return
        to_enter[state] = None
        if state.kind == COMPOUND:
            if state.initial_actions:
                content[state] = state.initial_actions
            initial = [self.by_name[n] for n in state.initial]
            for s in initial:
                self._add_descendants(s, to_enter, history, content)
            for s in initial:
                self._add_ancestors(s, state, to_enter, history, content)
        elif state.kind == PARALLEL:
            for child in state.proper_children():
                if not any(s.is_descendant_of(child) for s in to_enter):
                    self._add_descendants(child, to_enter, history, content)

    def _add_ancestors(self, state: State, ancestor: State | None, to_enter: dict,
                       history: dict, content: dict) -> None:
        for anc in state.ancestors():
            if anc is ancestor or anc is self.root:
                break
            to_enter[anc] = None
            if anc.kind == PARALLEL:
                for child in anc.proper_children():
                    if not any(s.is_descendant_of(child) for s in to_enter):
                        self._add_descendants(child, to_enter, history, content)

    # -- steps -----------------------------------------------------------

    def initial_step(self) -> Step:
        """Entering the scheme: the root's initial transition."""
        start = Transition(self.root, None, targets=self.root.initial,
                           actions=self.root.initial_actions)
        return self.microstep(Snapshot(frozenset()), [start])

    def microstep(self, snapshot: Snapshot, enabled: list[Transition]) -> Step:
        active = set(snapshot.active)
        history = dict(snapshot.history)
        exits = sorted(self.exit_set(active, enabled, history), key=_order, reverse=True)
        for s in exits:
            for h in s.children:
                if h.kind == HISTORY:
                    if h.history == "deep":
                        history[h] = frozenset(x for x in active
                                               if x.is_atomic and x.is_descendant_of(s))
                    else:
                        history[h] = frozenset(x for x in active if x.parent is s)
        active.difference_update(exits)
        entries: list[tuple[str, object]] = []
        to_enter, content = self.entry_set(enabled, history)
        for s in sorted(to_enter, key=_order):
            active.add(s)
            entries.append((ENTER, s))
            if s in content:
                entries.append((ACTIONS, content[s]))
            if s.invokes:
                entries.append((INVOKE, s))
            if s.kind != FINAL:
                continue
            parent = s.parent
            assert parent is not None
            if parent is self.root:
                entries.append((FINISH, s))
                continue
            done = f"done.state.{parent.name}"
            entries.append((DONE, (done, s)) if s.donedata is not None else (RAISE, done))
            grand = parent.parent
            if grand is not None and grand.kind == PARALLEL and all(
                    _in_final(c, active) for c in grand.proper_children()):
                entries.append((RAISE, f"done.state.{grand.name}"))
        target = Snapshot(frozenset(active), frozenset(history.items()))
        return Step(tuple(exits), tuple(t for t in enabled if t.actions), tuple(entries), target)


def _in_final(state: State, active: set[State]) -> bool:
    if state.kind == COMPOUND:
        return any(c.kind == FINAL and c in active for c in state.children)
    if state.kind == PARALLEL:
        return all(_in_final(c, active) for c in state.proper_children())
    return False

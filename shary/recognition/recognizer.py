"""Human action recognition: what people are doing, from the facts perception changes.

JAHRVIS's Human Actions Recognition (Section VI-B), on the fact base:

* it subscribes to **exactly the predicates the action models name** (and the
  ``type`` facts that say who is a Human), through the fact base's change
  notification: it never polls and never runs a query per change;
* it keeps **candidates**: one action model with its roles bound to entities
  (``place(alice, cube-1, red-cube)``), each *possibly started*, *possibly
  progressing* or *possibly achieved*;
* a **Move** starts a candidate (roles the move leaves open are bound from the
  preconditions that hold), a **ProgEffect** moves it to progressing, a
  **NecessEffect** achieves it (when all the necessary effects hold);
* an effect seen **without a start** is attributed, in this order, to the
  agent the effect names (``isHolding(alice, cube)``), to the agent for whom
  the action's preconditions held a moment before (who was holding the cube),
  to a human who was **near the object** (the paper's criterion: the models'
  ``near`` facts within ``near.within``), or to nobody.  An effect whose
  author is a robot is not a human action and is not recognized;
* it is **robust to flicker**: a fact that vanishes and comes back within
  ``settle`` is the same fact, not a new effect (``isHolding`` toggling ten
  times during a place is one place, and the hold coming back is not a second
  pick); a removal that no candidate explains counts only once it has lasted
  ``settle``; a candidate already in a state is not entered in it again; and
  an action achieved with the same entities within ``forget`` is achieved
  again only if a movement starts it again (a hold seen back after a long gap
  in perception is not a second pick).

Every change of a candidate's state is a :class:`Recognition`: written to the
context log (kind ``recognition``, read by ``shary log`` and drawn as the
human's lane of the timeline) and handed to the listeners (the human plan
manager will be one).  Candidates that neither move on nor end within
``forget`` are dropped (``abandoned``); when a candidate is achieved, the
agent's other candidates on an entity of it, of any action, are dropped with it
(they were the same gesture seen two ways).  The roles of one action are played
by different entities (a stick is never placed on itself).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from itertools import count
from typing import Any, NamedTuple

from shary.facts.database import FactDatabase, FactEvent, Subscription
from shary.recognition.memory import FactMemory
from shary.recognition.models import ActionModels, Fact, HumanActionModel

__all__ = ["STATES", "Candidate", "Recognition", "Recognizer"]

STATES = ("started", "progressing", "achieved", "abandoned")
"""A candidate's states, in the order they may be reached (abandoned: dropped unfinished)."""

_RANK = {"started": 0, "progressing": 1, "achieved": 2}
_TYPES = ("type", "rdf:type")


class Recognition(NamedTuple):
    """One candidate entering a state: what the log and the listeners receive."""

    time: float
    candidate: str
    """The candidate's id (``c1``, ``c2`` …): its rows in the log belong together."""
    state: str
    action: str
    action_class: str
    agent: str | None
    """The human it is attributed to; None: an effect nobody is known to have caused."""
    params: dict[str, Any]
    """role -> entity (None for a role nothing has bound yet)."""
    cause: str
    """What made the change: "move", "progress", "necessary" (seen), "near"/"before"
    (attributed by the criterion), "nobody", "forget", "achieved-other"."""
    fact: str
    """The fact whose change caused it, ``predicate(subject, object)`` (``not`` for a removal)."""


@dataclass
class Candidate:
    """An action model with bound roles, in one of the states."""

    id: str
    model: HumanActionModel
    binding: dict[str, Any]
    state: str
    since: float
    """When it was first seen (started, or an effect seen without a start)."""
    touched: float
    """When a change last concerned it (``forget`` counts from here)."""
    attributed: str = ""
    """How an effect seen without a start was attributed ("seen", "before", "near",
    "nobody"); empty when a movement started it."""

    @property
    def agent(self) -> Any:
        return self.binding.get(self.model.agent)

    def key(self) -> tuple:
        return (self.model.name, *(self.binding.get(role) for role in self.model.roles))


@dataclass
class _Trigger:
    model: HumanActionModel
    kind: str  # "move", "progress", "necessary"
    fact: Fact
    gate: tuple[Fact, str] | None = None
    """For a move: a precondition that completes a role the move leaves open, and that
    role's class; the move can start this model only if something of that class
    completes it (the cube held decides between place-cube and place-bottle)."""


def _gate(model: HumanActionModel, fact: Fact) -> tuple[Fact, str] | None:
    bound = {fact.subject, fact.object}
    for pre in model.precond:
        if not pre.negated and (pre.subject in bound) != (pre.object in bound):
            missing = pre.object if pre.subject in bound else pre.subject
            return pre, model.classes[missing]
    return None


class Recognizer:
    """Recognizes human actions from fact changes (see the module's documentation)."""

    def __init__(self, models: ActionModels, facts: FactDatabase, *,
                 perspective: str = "robot", clock: Callable[[], float],
                 record: Callable[..., Any] | None = None):
        self.models = models
        self.facts = facts
        self.perspective = perspective
        self.clock = clock
        self.record = record
        self.listeners: list[Callable[[Recognition], Any]] = []
        """Told of every recognition, after it is logged."""
        self.candidates: dict[str, dict[tuple, Candidate]] = {n: {} for n in models.human}
        """Live candidates (started or progressing) by model name, then key."""
        self.achieved: list[Recognition] = []
        """Every achievement so far, in order (the paper's *possibly achieved* list)."""
        self._store = FactMemory()
        self._reports = 0
        # (predicate, change) -> (side, class) -> triggers: an effect or move is looked up
        # by the class of the entity in its non-agent role (side 0: subject, 1: object;
        # None: the fact names the agent alone), so that with a model per kind of object
        # a change meets only the models of its object's kind
        self._triggers: dict[tuple[str, str], dict[tuple[int, str] | None, list[_Trigger]]] = {}
        for model in models.human.values():
            for kind in ("move", "progress", "necessary"):
                for fact in getattr(model, kind):
                    key = (fact.predicate, "removed" if fact.negated else "added")
                    side = (0 if fact.subject != model.agent else
                            1 if fact.object != model.agent else None)
                    role = None if side is None else (fact.subject, fact.object)[side]
                    by_class = self._triggers.setdefault(key, {})
                    index = None if side is None else (side, model.classes[role])
                    gate = _gate(model, fact) if kind == "move" else None
                    by_class.setdefault(index, []).append(_Trigger(model, kind, fact, gate))
        self._order = {id(t): i for i, t in enumerate(
            t for by_class in self._triggers.values() for ts in by_class.values() for t in ts)}
        self._near = [(f.predicate, f.subject == "Human") for f in models.near]
        self._near_predicates = {f.predicate for f in models.near}
        self._near_seen: dict[tuple[Any, Any], float] = {}  # (human, object) -> last near
        self._types: dict[Any, frozenset[str]] = {}
        self._subscriptions: list[Subscription] = []
        self._ids = count(1)
        self._swept = 0.0
        self._done: dict[str, list[tuple[dict[str, Any], float]]] = {n: [] for n in models.human}
        """Recent achievements by model: an effect that is their tail is not a new action."""
        self._recent = max(models.settle, models.near_within)
        self._completions: dict[tuple[Any, Any, Any], list[Any]] = {}
        self._gate_classes: dict[tuple[Any, Any, Any], frozenset[str] | None] = {}
        self._pending: list[tuple[_Trigger, dict[str, Any], float]] = []
        """Removals that no candidate explains, waiting to last ``settle`` (flicker)."""

    # -- the three lists (JAHRVIS's HAR outputs) --------------------------------------------------

    @property
    def possibly_started(self) -> list[Candidate]:
        return self._live("started")

    @property
    def possibly_progressing(self) -> list[Candidate]:
        return self._live("progressing")

    def _live(self, state: str) -> list[Candidate]:
        return [c for by_key in self.candidates.values() for c in by_key.values()
                if c.state == state]

    # -- subscribing ------------------------------------------------------------------------------

    def start(self) -> None:
        """Read the current facts of the models' predicates, then follow their changes."""
        predicates = self.models.predicates()
        wanted = set(predicates)
        for s, p, o in self.facts.triples(self.perspective):
            if p in wanted:
                self._store.add(s, p, o)
                if p in self._near_predicates:
                    self._note_near(s, p, o)
        for predicate in (*predicates, *_TYPES):
            self._subscriptions.append(self.facts.subscribe(
                self.on_fact, predicate=predicate, perspective=self.perspective))

    def stop(self) -> None:
        for subscription in self._subscriptions:
            self.facts.unsubscribe(subscription)
        self._subscriptions.clear()

    # -- one change -------------------------------------------------------------------------------

    def on_fact(self, event: FactEvent) -> None:
        """Take one change of a subscribed predicate into account."""
        kind, s, p, o = event.kind, event.subject, event.predicate, event.object
        if p in _TYPES:
            self._types.pop(s, None)
            return
        now = self.clock()
        store = self._store
        self._completions.clear()  # what preconditions complete, for this change's models
        self._gate_classes.clear()
        if kind == "added":
            # a fact back within `settle` of vanishing is the same fact: flicker, not an effect
            gone = store.add(s, p, o)
            if p in self._near_predicates:
                self._note_near(s, p, o)
            if gone is not None and now - gone < self.models.settle:
                return
        else:
            store.remove(s, p, o, now)
            if p in self._near_predicates:
                self._note_near(s, p, o)
        if self._pending:
            self._settled(now)
        if now - self._swept >= 1.0:
            self._sweep(now)
        by_class = self._triggers.get((p, kind))
        if not by_class:
            return
        for trigger in self._matching(by_class, s, o):
            fact = trigger.fact
            if fact.subject == fact.object and s != o:
                continue
            binding = {fact.subject: s, fact.object: o}
            if trigger.kind == "move":
                self._move(trigger, binding, now)
            else:
                self._effect(trigger, binding, now)

    def _matching(self, by_class: dict, s: Any, o: Any) -> list[_Trigger]:
        """The triggers whose non-agent role's class the entity there is (every one, for
        an entity of unknown type), in the models' order."""
        buckets = [by_class[None]] if None in by_class else []
        for side, entity in ((0, s), (1, o)):
            closure = self._closure(entity)
            if closure:
                buckets += [by_class[(side, cls)] for cls in closure if (side, cls) in by_class]
            else:
                buckets += [triggers for key, triggers in by_class.items()
                            if key is not None and key[0] == side]
        if len(buckets) == 1:
            return buckets[0]  # the common case: one kind of object, already in order
        order = self._order
        return sorted((t for bucket in buckets for t in bucket), key=lambda t: order[id(t)])

    def _gate_open(self, gate: tuple[Fact, str], binding: dict[str, Any], now: float) -> bool:
        """Whether something of the gate's class completes its precondition (the classes
        of what completes one pattern are worked out once per change, for all models)."""
        pre, cls = gate
        key = (binding.get(pre.subject), pre.predicate, binding.get(pre.object))
        classes = self._gate_classes.get(key)
        if classes is None:
            values = self._completions.get(key)
            if values is None:
                values = self._completions[key] = self._store.completing(
                    *key, now, self.models.settle)
            closures = [self._closure(v) for v in values]
            classes = self._gate_classes[key] = (
                None if any(not c for c in closures) else frozenset().union(*closures))
        return classes is None or cls in classes  # None: something of unknown type

    def _move(self, trigger: _Trigger, binding: dict[str, Any], now: float) -> None:
        model = trigger.model
        if not self._is(binding.get(model.agent), model.agent, agent=True):
            return
        live = self.candidates[model.name]
        found = live and next((c for c in live.values()
                               if all(c.binding.get(role) in (None, value)
                                      for role, value in binding.items())), None)
        if found:  # seen under way already (an effect came first): the same one
            del live[found.key()]
            found.binding, found.touched = {**found.binding, **binding}, now
            live[found.key()] = found
            return
        if trigger.gate is not None and not self._gate_open(trigger.gate, binding, now):
            return
        for full in self._bind(model, binding, now):
            key = (model.name, *(full.get(role) for role in model.roles))
            if key in live:
                live[key].touched = now
                continue
            candidate = Candidate(f"c{next(self._ids)}", model, full, "started", now, now)
            live[key] = candidate
            self._emit(candidate, "move", trigger.fact, now)

    def _effect(self, trigger: _Trigger, binding: dict[str, Any], now: float) -> None:
        model, state = trigger.model, ("progressing" if trigger.kind == "progress" else "achieved")
        classes = model.classes
        if not all(self._is(value, classes[role]) for role, value in binding.items()
                   if role != model.agent):
            return
        live = self.candidates[model.name]
        matches = [c for c in live.values()
                   if all(c.binding.get(role) in (None, value) for role, value in binding.items())]
        if matches:
            candidate = max(matches, key=lambda c: (_RANK[c.state], c.touched, c.id))
            if _RANK[candidate.state] >= _RANK[state]:
                candidate.touched = now
                return
            full = {**candidate.binding, **binding}
            if state == "achieved" and not self._necessary_hold(model, full):
                return
            del live[candidate.key()]
            candidate.binding, candidate.touched = full, now
            if state == "progressing":
                live[candidate.key()] = candidate
            self._enter(candidate, state, trigger.kind, trigger.fact, now)
            return
        if any(now - when <= self._recent and all(done.get(r) in (None, v)
                                                   for r, v in binding.items())
               for done, when in self._done[model.name]):
            return  # the tail of an action just achieved (the hold let go after the place)
        if trigger.fact.negated and state == "progressing":
            # a removal nothing started may be flicker: it counts once it has lasted `settle`
            self._pending.append((trigger, binding, now))
            return
        self._attribute_effect(trigger, binding, state, now)

    def _attribute_effect(self, trigger: _Trigger, binding: dict[str, Any], state: str,
                          now: float) -> None:
        """An effect no live candidate explains: a new candidate, if someone did it."""
        model, live = trigger.model, self.candidates[trigger.model.name]
        agent, cause = self._attribute(model, binding, now)
        if cause == "robot":
            return
        full = {**binding, model.agent: agent}
        if state == "achieved" and not self._necessary_hold(model, full):
            return
        if any(done == full for done, _ in self._done[model.name]):
            return  # achieved already, and not started again since: the effect came back
        candidate = Candidate(f"c{next(self._ids)}", model, full, state, now, now, cause)
        if state == "progressing":
            live[candidate.key()] = candidate
        self._emit(candidate, cause, trigger.fact, now)
        if state == "achieved":
            self._drop_siblings(candidate, now)

    def _settled(self, now: float) -> None:
        """Removals nothing started that have lasted ``settle``: attributed now (those
        whose fact came back were flicker and are forgotten)."""
        settle, store, waiting = self.models.settle, self._store, []
        for trigger, binding, when in self._pending:
            fact = trigger.fact
            s, o = binding[fact.subject], binding[fact.object]
            if store.gone.get((s, fact.predicate, o)) != when:
                continue  # came back since (flicker); a later removal has its own entry
            if now - when < settle:
                waiting.append((trigger, binding, when))
                continue
            live = self.candidates[trigger.model.name]
            if not any(all(c.binding.get(r) in (None, v) for r, v in binding.items())
                       for c in live.values()):
                self._attribute_effect(trigger, binding, "progressing", now)
        self._pending = waiting

    def _enter(self, candidate: Candidate, state: str, cause: str, fact: Fact | None,
               now: float) -> None:
        candidate.state = state
        self._emit(candidate, cause, fact, now)
        if state == "achieved":
            self._drop_siblings(candidate, now)

    # -- binding and attribution ------------------------------------------------------------------

    def _bind(self, model: HumanActionModel, binding: dict[str, Any],
              now: float) -> list[dict[str, Any]]:
        """Complete a binding through the preconditions that hold (or held ``settle``
        seconds ago or less): one binding per way they hold; none if a bound one fails."""
        results = [dict(binding)]
        settle, store, classes = self.models.settle, self._store, model.classes
        completions = self._completions
        for fact in model.precond:
            extended: list[dict[str, Any]] = []
            for current in results:
                s, o = current.get(fact.subject), current.get(fact.object)
                if fact.negated:
                    if s is None or o is None or not store.holds(s, fact.predicate, o):
                        extended.append(current)
                elif s is not None and o is not None:
                    if store.recently(s, fact.predicate, o, now, settle):
                        extended.append(current)
                elif s is None and o is None:
                    extended.append(current)
                else:
                    missing = fact.object if o is None else fact.subject
                    key = (s, fact.predicate, o)
                    values = completions.get(key)
                    if values is None:
                        values = completions[key] = store.completing(s, fact.predicate, o,
                                                                     now, settle)
                    for value in values:
                        if self._is(value, classes[missing], agent=missing == model.agent):
                            extended.append({**current, missing: value})
            results = extended
        return [r for r in results
                if all(self._is(v, classes[role]) for role, v in r.items()
                       if role != model.agent and v is not None) and _distinct(r, model)]

    def _attribute(self, model: HumanActionModel, binding: dict[str, Any],
                   now: float) -> tuple[Any, str]:
        """Who caused an effect seen without a start (see the module's documentation)."""
        agent = binding.get(model.agent)
        if agent is not None:
            return (agent, "seen") if self._is(agent, model.agent, agent=True) else (None, "robot")
        within = self.models.near_within
        for fact in model.precond:  # for whom did the preconditions hold a moment ago?
            if fact.negated or model.agent not in (fact.subject, fact.object):
                continue
            other = fact.object if fact.subject == model.agent else fact.subject
            value = binding.get(other)
            if value is None:
                continue
            s, o = (None, value) if fact.subject == model.agent else (value, None)
            for author in self._store.completing(s, fact.predicate, o, now, within):
                if self._is(author, model.agent, agent=True):
                    return author, "before"
                if self._is_agent(author):
                    return None, "robot"
        near: list[tuple[float, str]] = []
        for value in binding.values():
            for (human, obj), last in self._near_seen.items():
                if obj == value and (last == float("inf") or now - last <= within) \
                        and self._is(human, model.agent, agent=True):
                    near.append((last, human))
        if near:
            return max(near, key=lambda item: (item[0], item[1]))[1], "near"
        return None, "nobody"

    def _note_near(self, s: Any, p: Any, o: Any) -> None:
        """Keep when each human was last near each object (inf: near now)."""
        for predicate, human_first in self._near:
            if predicate != p:
                continue
            human, obj = (s, o) if human_first else (o, s)
            near_now = self._store.holds(s, p, o)
            self._near_seen[(human, obj)] = float("inf") if near_now else self.clock()

    def _necessary_hold(self, model: HumanActionModel, binding: dict[str, Any]) -> bool:
        store = self._store
        for fact in model.necessary:
            s, o = binding.get(fact.subject), binding.get(fact.object)
            if s is None or o is None:
                continue
            if store.holds(s, fact.predicate, o) == fact.negated:
                return False
        return True

    def _is(self, entity: Any, cls: str, *, agent: bool = False) -> bool:
        """Whether the fact base says ``entity`` is a ``cls`` (an entity whose type is not
        known passes, unless it must be the agent: only a known human acts)."""
        if entity is None:
            return not agent
        closure = self._closure(entity)
        return cls in closure if closure else not agent

    def _closure(self, entity: Any) -> frozenset[str]:
        """Every class ``entity`` is, by its ``type`` facts and the ontology (kept until
        its type changes)."""
        found = self._types.get(entity)
        if found is None:
            ontology = self.models.ontology
            types = {str(t) for predicate in _TYPES
                     for t in self.facts.objects(entity, predicate, self.perspective)}
            found = self._types[entity] = frozenset(
                types.union(*(ontology.superclasses(t) for t in types if t in ontology)))
        return found

    def _is_agent(self, entity: Any) -> bool:
        return self._is(entity, "Agent", agent=True)

    # -- ends -------------------------------------------------------------------------------------

    def _drop_siblings(self, achieved: Candidate, now: float) -> None:
        """The agent's other live candidates, of any action, on an entity of the achieved
        one: the gesture toward it was this action, seen another way too (the hand that
        went to the stick to put a cube on it was not picking the stick)."""
        values = {v for role, v in achieved.binding.items()
                  if role != achieved.model.agent and v is not None}
        for live in self.candidates.values():
            for key, other in list(live.items()):
                if other is achieved or other.agent not in (achieved.agent, None):
                    continue
                if values & {v for role, v in other.binding.items()
                             if role != other.model.agent}:
                    del live[key]
                    other.state = "abandoned"
                    self._emit(other, "achieved-other", None, now)

    def _sweep(self, now: float) -> None:
        """Drop candidates untouched for ``forget`` seconds, and forget old vanished facts."""
        self._swept = now
        forget = self.models.forget
        for live in self.candidates.values():
            for key, candidate in list(live.items()):
                if now - candidate.touched >= forget:
                    del live[key]
                    candidate.state = "abandoned"
                    self._emit(candidate, "forget", None, now)
        self._store.forget(now - self._recent)
        kept = max(forget, self._recent)
        for name, done in self._done.items():
            self._done[name] = [(b, t) for b, t in done if now - t <= kept]

    def report(self, agent: str, action: str, objects: list[Any], by: str) -> Recognition:
        """A person's action that someone saw, not the perception: an operator standing in
        for it (a Wizard-of-Oz study, an action the sensors cannot see).  Achieved at once,
        logged like any recognition (cause ``reported by BY``) and given to the listeners
        (the human plan manager matches it to the plan).  ``action`` is any name of the
        action's class (a planner's ``Place``), ``objects`` fill its roles in order; a
        ValueError says when no human action model is that action."""
        ontology = self.models.ontology
        cls = ontology.action_class(action)
        model = next((m for m in self.models.human.values()
                      if cls is not None and ontology.action_class(m.name) == cls), None)
        if model is None:
            raise ValueError(f"no human action model is {action!r}")
        roles = {p.role: o for p, o in zip(ontology.parameters(cls), objects, strict=False)}
        now = self.clock()
        self._reports += 1
        candidate = Candidate(f"reported-{self._reports}", model,
                              {model.agent: agent, **{role: roles.get(role)
                                                      for role, _ in model.params}},
                              "achieved", now, now)
        self._emit(candidate, f"reported by {by}", None, now)
        return self.achieved[-1]

    def _emit(self, candidate: Candidate, cause: str, fact: Fact | None, now: float) -> None:
        model = candidate.model
        params = {role: candidate.binding.get(role) for role, _ in model.params}
        shown = "" if fact is None else _shown(fact, candidate.binding)
        recognition = Recognition(now, candidate.id, candidate.state, model.name,
                                  model.action_class, candidate.agent, params, cause, shown)
        if candidate.state == "achieved":
            self.achieved.append(recognition)
            self._done[model.name].append((dict(candidate.binding), now))
        if self.record is not None:
            self.record("recognition", agent=recognition.agent, candidate=candidate.id,
                        state=candidate.state, action=model.name,
                        action_class=model.action_class,
                        params={k: None if v is None else str(v) for k, v in params.items()},
                        cause=cause, fact=shown or None)
        for listener in self.listeners:
            listener(recognition)


def _distinct(binding: dict[str, Any], model: HumanActionModel) -> bool:
    """Whether the roles of an action are played by different entities: a stick is not
    placed on itself, however the hand moving toward it while holding it reads."""
    values = [v for role, v in binding.items() if role != model.agent and v is not None]
    return len(values) == len(set(values))


def _shown(fact: Fact, binding: dict[str, Any]) -> str:
    s, o = binding.get(fact.subject, fact.subject), binding.get(fact.object, fact.object)
    return f"{'not ' if fact.negated else ''}{fact.predicate}({s}, {o})"

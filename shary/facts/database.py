"""The fact database: what each agent believes about the world, and its changes as events.

SHARY keeps a-priori knowledge (places, furniture, objects) beside contextual
facts that perception adds and removes (positions, who holds what, who looks
at whom), and it keeps them *per agent*: what the robot believes and what it
estimates each human believes.  Here that is one :class:`rdflib.Dataset`:

* the **a-priori graph** is the dataset's default graph, filled from Turtle
  files (:meth:`FactDatabase.load_turtle` with ``perspective=None``);
* every **perspective** (an agent's name: ``"robot"``, ``"human-1"`` …) is a
  named graph ``urn:shary:perspective:NAME``.

**How perspectives see a-priori knowledge.**  A perspective *starts as a copy
of the a-priori graph* the first time something writes to it, then evolves on
its own: ``add``, ``remove`` and ``set`` change only that perspective.  A
perspective nobody wrote to yet reads as the a-priori graph.  A union of the
a-priori graph and the agent's graph would be the other choice, but a union
cannot *forget*: an a-priori fact such as "the bottle is on the coffee table"
could never be removed or replaced by ``set`` when perception sees the bottle
move.  With copies, every agent knows the a-priori world at the start and its
beliefs may then diverge from it and from each other's.  Turtle loaded into
the a-priori graph later is copied into every existing perspective as well.
Loading is setting up knowledge, not a change seen in the world, so it
delivers no events; load before the run starts.

**Terms.**  Users and recipes write short names: ``"coffee-table"`` and
``"isOn"`` are IRIs of the world namespace (prefix ``w:``); ``"w:isOn"`` or
``"rdf:type"`` use a known prefix (``w``, ``rdf``, ``rdfs``, ``xsd``,
``owl``); ``"http://…"``, ``"https://…"`` and ``"urn:…"`` are full IRIs;
Python ``bool``, ``int`` and ``float`` values are typed literals, and rdflib
terms are taken as they are (use ``rdflib.Literal("text")`` for a string
literal: a Python ``str`` always names a resource).  :meth:`FactDatabase.name`
turns a term back into what :meth:`FactDatabase.term` accepts, so that
``term(name(t)) == t``: a short name, a prefixed name, a full IRI, a Python
``bool``/``int``/``float``, or the rdflib term itself for any other literal
(strings, decimals, dates) and for blank nodes.  Mind that Turtle's ``0.5``
is an ``xsd:decimal`` while Python's ``0.5`` is an ``xsd:double``: write
``5.0e-1`` in files whose numbers the engine compares with Python floats.

**Where facts live.**  Each perspective keeps its own index in front of its
rdflib graph (:class:`shary.facts.perspective.Perspective`), which answers
:meth:`holds`, :meth:`objects`, :meth:`triples` and tells whether a change
changes anything; the rdflib graph stays the store for SPARQL and export,
brought up to date just before it is read (:meth:`select`, :attr:`dataset`).
Turtle files are read by :mod:`shary.facts.turtle`.  ``docs/architecture.md`` has
the figures of the alternatives measured (oxrdflib, pyoxigraph).

**Derived structures.**  :meth:`FactDatabase.derived` keeps a consumer's own
index of one perspective (the referring expressions' index, say) current:
built once from the perspective's facts, then told of each change of the
predicates it follows as the change is made, before any event.

**Events.**  Every addition and deletion made through :meth:`add`,
:meth:`remove` and :meth:`set` is delivered as a :class:`FactEvent` to the
subscribers whose pattern matches.  Monitors react to those events; they never
run a SPARQL query per event (rdflib's SPARQL engine costs milliseconds, see
``../shared/DESIGN.md``), which is why subscriptions are indexed by
(subject, predicate): one change looks up four buckets ((s, p), (any, p),
(s, any), (any, any)) and only tests the subscriptions found there.

**Order of delivery.**  Events are delivered *after* the change that caused
them is complete (for :meth:`set`: all removals and the addition), in the
order of the changes, and each event to its subscribers in the order they
subscribed.  A callback may change facts: its changes are applied at once
(later callbacks and queries see them) but their events are queued behind the
ones already waiting (first in, first out) and delivered when the current
event has reached all its subscribers.  So the sequence of events every
subscriber sees is the same for the same sequence of calls, and no callback is
ever entered twice at once.  A subscription cancelled during delivery receives
nothing more, even of an event already under way; one made during delivery
receives the events that are delivered after it.

The database is single-threaded, like the rest of the engine's core.
"""

from __future__ import annotations

import functools
import logging
import os
import re
import typing
from collections import deque
from collections.abc import Callable, Iterable
from itertools import count
from urllib.parse import quote

from pyparsing import ParseException
from rdflib import OWL, RDF, RDFS, XSD, Dataset, Literal, URIRef
from rdflib.plugins.sparql import prepareQuery
from rdflib.plugins.sparql.sparql import Query
from rdflib.term import Node

from shary.facts.perspective import Perspective
from shary.facts.turtle import Triple, read_turtle

__all__ = ["FactDatabase", "FactEvent", "Subscription", "Value"]

log = logging.getLogger(__name__)

D = typing.TypeVar("D")

Value = str | int | float | bool | Node
"""What the engine speaks: short or prefixed names, full IRIs, Python numbers
and booleans, or rdflib terms (string literals, blank nodes)."""

EventKind = typing.Literal["added", "removed"]

_PREFIXES = {"rdf": str(RDF), "rdfs": str(RDFS), "xsd": str(XSD), "owl": str(OWL)}
"""Fixed, so that what a name means does not depend on which files were loaded."""

_NAME = re.compile(r"\w(?:[\w.-]*[\w-])?")
"""A short name (the local part of a prefixed name): no spaces, colons or slashes."""

_PERSPECTIVE_GRAPH = "urn:shary:perspective:"



class FactEvent(typing.NamedTuple):
    """One fact added to or removed from one perspective, in short names.

    A named tuple rather than a frozen dataclass: one is made per change that
    some subscriber hears, and a tuple is built three times faster.
    """

    kind: EventKind
    subject: Value
    predicate: Value
    object: Value
    perspective: str


class Subscription:
    """A standing interest in fact events that match a pattern; give it to ``unsubscribe``.

    The pattern is kept as rdflib terms (the index keys), so that matching a
    change never converts names.
    """

    __slots__ = ("callback", "perspective", "kind", "active", "_key", "_object", "_order")

    def __init__(self, callback: Callable[[FactEvent], object],
                 key: tuple[Node | None, Node | None], obj: Node | None,
                 perspective: str | None, kind: EventKind | None, order: int):
        self.callback = callback
        self.perspective = perspective
        self.kind = kind
        self.active = True
        """False once unsubscribed: a cancelled subscription receives nothing more."""
        self._key = key
        self._object = obj
        self._order = order


@functools.lru_cache(maxsize=256)
def _prepare_select(text: str, namespace: str) -> Query:
    """Parse a SELECT query once: recipes run the same few queries over and over."""
    try:
        query = prepareQuery(text, initNs={"w": namespace, **_PREFIXES})
    except ParseException as err:
        raise ValueError(f"not a SPARQL SELECT query: {err}") from None
    if query.algebra.name != "SelectQuery":
        kind = query.algebra.name.removesuffix("Query").upper()
        raise ValueError(f"only SPARQL SELECT queries are run here, not {kind}")
    return query


def _order(term: Node) -> str:
    """A total, stable order on terms, so that lists and events never depend on hashing."""
    return term.n3()


class FactDatabase:
    """A-priori knowledge and per-agent contextual facts, with change events by pattern.

    See the module's documentation for the perspective rule, the terms and the
    order of delivery.
    """

    def __init__(self, namespace: str = "http://shary.dev/world#"):
        self._namespace = namespace
        self._prefixes = {"w": namespace, **_PREFIXES}
        self._dataset = Dataset()
        self._apriori = Perspective(self._dataset.default_graph)
        self._perspectives: dict[str, Perspective] = {}
        # Caches both ways between names and IRIs: a world's vocabulary is small
        # and the same names come back with every perception update.
        self._terms: dict[str, Node] = {}
        self._names: dict[URIRef, str] = {}
        self._index: dict[tuple[Node | None, Node | None], list[Subscription]] = {}
        self._orders = count()
        self._queue: deque[tuple[EventKind, Node, Node, Node, str]] = deque()
        self._delivering = False

    @property
    def dataset(self) -> Dataset:
        """The underlying dataset (a-priori default graph, one named graph per
        perspective), for exporting it, e.g. as TriG; change facts through the
        database's methods, or subscribers (and the database's own index) will
        not hear of it."""
        self._apriori.sync()
        for perspective in self._perspectives.values():
            perspective.sync()
        return self._dataset

    # -- terms -----------------------------------------------------------------------------------

    def term(self, value: Value) -> Node:
        """The rdflib term for a short name, prefixed name, full IRI, number or boolean."""
        if type(value) is str:  # the common case first: isinstance(…, Node) is an ABC check
            term = self._terms.get(value)
            if term is None:
                term = self._terms[value] = self._parse_name(value)
            return term
        if type(value) is URIRef or type(value) is Literal:  # before the slower ABC check
            return value
        if isinstance(value, Node):
            return value
        if isinstance(value, str):
            term = self._terms.get(value)
            if term is None:
                term = self._terms[value] = self._parse_name(value)
            return term
        if isinstance(value, (bool, int, float)):
            return Literal(value)
        raise TypeError(f"cannot make an RDF term of {type(value).__name__} {value!r}")

    def _parse_name(self, text: str) -> URIRef:
        prefix, colon, local = text.partition(":")
        if not colon:
            if _NAME.fullmatch(text):
                return URIRef(self._namespace + text)
            raise ValueError(f"{text!r} is not a name: use letters, digits, '_', '-' and '.' "
                             "(and rdflib.Literal for a string literal)")
        if prefix in self._prefixes:
            if _NAME.fullmatch(local):
                return URIRef(self._prefixes[prefix] + local)
            raise ValueError(f"{text!r}: {local!r} is not a name")
        if (local.startswith("//") or prefix == "urn") and not any(c.isspace() for c in text):
            return URIRef(text)
        known = ", ".join(sorted(self._prefixes))
        raise ValueError(f"{text!r}: unknown prefix {prefix!r} (known: {known}); "
                         "a full IRI starts with http://, https:// or urn:")

    def name(self, term: Node) -> Value:
        """The inverse of :meth:`term`: the short name, prefixed name or full IRI of an
        IRI, the Python value of a bool/int/float literal, any other term as it is."""
        if isinstance(term, URIRef):
            try:
                return self._names[term]
            except KeyError:
                name = self._names[term] = self._short(term)
                return name
        if isinstance(term, Literal):
            value = term.toPython()
            if isinstance(value, (bool, int, float)):
                return value
        return term

    def _short(self, iri: URIRef) -> str:
        if iri.startswith(self._namespace) and _NAME.fullmatch(iri[len(self._namespace):]):
            return str(iri[len(self._namespace):])
        for prefix, namespace in _PREFIXES.items():
            if iri.startswith(namespace) and _NAME.fullmatch(iri[len(namespace):]):
                return f"{prefix}:{iri[len(namespace):]}"
        return str(iri)

    def _triple(self, s: Value, p: Value, o: Value) -> Triple:
        return self.term(s), self.term(p), self.term(o)

    # -- perspectives ----------------------------------------------------------------------------

    def perspectives(self) -> list[str]:
        """The perspectives written to so far, in the order they were created."""
        return list(self._perspectives)

    def _view(self, perspective: str) -> Perspective:
        """The perspective to read from (the a-priori graph's until it diverges)."""
        return self._perspectives.get(perspective, self._apriori)

    def _writable(self, perspective: str) -> Perspective:
        """The perspective to write to, created as a copy of the a-priori graph."""
        found = self._perspectives.get(perspective)
        if found is None:
            if not isinstance(perspective, str) or not perspective:
                raise ValueError(f"a perspective is an agent's name, not {perspective!r}")
            graph = self._dataset.graph(URIRef(_PERSPECTIVE_GRAPH + quote(perspective, safe="")))
            found = self._perspectives[perspective] = Perspective(graph, self._apriori)
        return found

    # -- loading ---------------------------------------------------------------------------------

    def load_turtle(self, path: str | os.PathLike[str], perspective: str | None = None) -> int:
        """Load a Turtle file into the a-priori graph (``None``) or one perspective.

        Returns the number of triples the file holds.  The file is parsed in
        full before anything changes, so a refused file leaves the database
        as it was.  Delivers no events (see the module's documentation).
        """
        file = os.fspath(path)
        parsed = read_turtle(file)
        if perspective is None:
            self._apriori.load(parsed)
            for view in self._perspectives.values():
                view.load(parsed)
        else:
            self._writable(perspective).load(parsed)
        return len(parsed)

    # -- reading ---------------------------------------------------------------------------------

    def holds(self, s: Value, p: Value, o: Value, perspective: str = "robot") -> bool:
        """Whether the agent of ``perspective`` believes the fact."""
        return self._triple(s, p, o) in self._view(perspective).triples

    def objects(self, s: Value, p: Value, perspective: str = "robot") -> list[Value]:
        """Every object of (s, p) in a perspective, as names, in a stable order."""
        objects = self._view(perspective).objects.get((self.term(s), self.term(p)))
        if not objects:
            return []
        return [self.name(o) for o in sorted(objects, key=_order)]

    def triples(self, perspective: str = "robot") -> list[tuple[Value, Value, Value]]:
        """Every fact of a perspective, in short names (a run's final state, a dump)."""
        return sorted(((self.name(s), self.name(p), self.name(o))
                       for s, p, o in self._view(perspective).triples), key=str)

    def select(self, sparql: str, perspective: str = "robot",
               **bindings: Value) -> list[dict[str, Value | None]]:
        """Run a SPARQL SELECT over one perspective; rows map each variable to a name.

        ``w:``, ``rdf:``, ``rdfs:``, ``xsd:`` and ``owl:`` are declared.  Keyword
        arguments bind variables before the query runs (SPARQL's initBindings),
        so values never have to be pasted into query text.  A variable left
        unbound in a row maps to None.  Rows come in the engine's order; write
        ORDER BY when the order matters.  Anything but SELECT raises ValueError:
        facts change through :meth:`add` and :meth:`remove`, which deliver events.
        """
        query = _prepare_select(sparql, self._namespace)
        init = {variable: self.term(value) for variable, value in bindings.items()}
        result = self._view(perspective).sync().query(query, initBindings=init)
        names = [str(variable) for variable in result.vars or ()]
        return [{name: None if value is None else self.name(value)
                 for name, value in zip(names, row, strict=True)}
                for row in result]

    def derived(self, key: typing.Hashable, perspective: str,
                build: Callable[[list[tuple[Value, Value, Value]]], D],
                predicates: typing.Iterable[Value],
                changed: Callable[[D, bool, Value, Value, Value], object]) -> D:
        """A structure derived from one perspective's facts with ``predicates`` (an index),
        built once and kept current by every later change.

        ``build(triples)`` makes it from the perspective's facts with those
        predicates (in short names, unordered); ``changed(structure, added,
        s, p, o)`` applies one addition (``added``) or removal to it.  It is
        told of a change as the change is made, before any event is
        delivered, so a subscriber reading the structure never sees it lag
        behind :meth:`holds`.  Why not rebuild it when needed: a robot speaks
        about a world of thousands of facts, and a sentence must not cost
        the whole world (the kernel benchmark starts 10,000 tasks, each of
        which speaks).  Loading Turtle drops the structure; the next call
        builds it again.  ``key`` tells structures apart (a class, say).
        """
        view = self._view(perspective)
        found = view.derived.get(key)
        if found is not None:
            return typing.cast(D, found)
        wanted = {self.term(p) for p in predicates}
        name = self.name
        structure = build([(name(s), name(p), name(o)) for s, p, o in view.triples
                           if p in wanted])

        def watch(added: bool, triple: Triple) -> None:
            changed(structure, added, name(triple[0]), name(triple[1]), name(triple[2]))

        view.derived[key] = structure
        for predicate in wanted:
            view.watchers.setdefault(predicate, []).append(watch)
        return structure

    # -- changing --------------------------------------------------------------------------------

    def add(self, s: Value, p: Value, o: Value, perspective: str = "robot") -> bool:
        """Add a fact to a perspective; True (and an "added" event) when it is new."""
        triple = self._triple(s, p, o)
        if not self._writable(perspective).add(triple):
            return False
        self._deliver(("added", *triple, perspective))
        return True

    def remove(self, s: Value, p: Value, o: Value, perspective: str = "robot") -> bool:
        """Remove a fact from a perspective; True (and a "removed" event) when it was there."""
        triple = self._triple(s, p, o)
        if not self._writable(perspective).remove(triple):
            return False
        self._deliver(("removed", *triple, perspective))
        return True

    def set(self, s: Value, p: Value, o: Value, perspective: str = "robot") -> bool:
        """Make ``o`` the only object of (s, p), for functional predicates (a position,
        what an object is on).

        Removes every other object first (in a stable order), then adds ``o``;
        all these events are delivered once the whole change is made, so no
        subscriber sees (s, p) without an object in between.  Returns True when
        the fact (s, p, o) was new.
        """
        s_term, p_term, o_term = self._triple(s, p, o)
        view = self._writable(perspective)
        changes: list[tuple[EventKind, Node, Node, Node, str]] = []
        for old in sorted(view.objects.get((s_term, p_term), ()), key=_order):
            if old != o_term:
                view.remove((s_term, p_term, old))
                changes.append(("removed", s_term, p_term, old, perspective))
        new = view.add((s_term, p_term, o_term))
        if new:
            changes.append(("added", s_term, p_term, o_term, perspective))
        self._deliver(*changes)
        return new

    def change(self, removed: Iterable[tuple[Value, Value, Value]],
               added: Iterable[tuple[Value, Value, Value]],
               perspective: str = "robot") -> int:
        """Remove some facts and add others as one change, in the order given; how many
        facts changed.

        As for :meth:`set`, every event is delivered once the whole change is made: no
        subscriber sees the perspective half-changed (a person's old position gone and
        the new one not there yet).  What a perception topic's message changes
        (:mod:`shary.ros.perception`)."""
        view = self._writable(perspective)
        changes: list[tuple[EventKind, Node, Node, Node, str]] = []
        for s, p, o in removed:
            triple = self._triple(s, p, o)
            if view.remove(triple):
                changes.append(("removed", *triple, perspective))
        for s, p, o in added:
            triple = self._triple(s, p, o)
            if view.add(triple):
                changes.append(("added", *triple, perspective))
        if changes:
            self._deliver(*changes)
        return len(changes)

    # -- events ----------------------------------------------------------------------------------

    def subscribe(self, callback: Callable[[FactEvent], object], subject: Value | None = None,
                  predicate: Value | None = None, object: Value | None = None,
                  perspective: str | None = None,
                  kind: EventKind | None = None) -> Subscription:
        """Call ``callback(event)`` for every change matching the pattern (None: anything);
        ``kind`` ("added" or "removed") keeps only that kind of change."""
        if kind not in (None, "added", "removed"):
            raise ValueError(f"a change is 'added' or 'removed', not {kind!r}")
        key = (None if subject is None else self.term(subject),
               None if predicate is None else self.term(predicate))
        subscription = Subscription(callback, key, None if object is None else self.term(object),
                                    perspective, kind, next(self._orders))
        self._index.setdefault(key, []).append(subscription)
        return subscription

    def log_changes(self, record: Callable[..., object]) -> Subscription:
        """Write every change as a ``fact-added`` / ``fact-removed`` row through
        ``record(kind, **data)`` (a context log's): the rows the timeline's attention band,
        the console's Facts panel and a run's story read."""
        def logged(event: FactEvent) -> None:
            record(f"fact-{event.kind}", perspective=event.perspective, s=str(event.subject),
                   p=str(event.predicate), o=str(event.object))
        return self.subscribe(logged)

    def unsubscribe(self, subscription: Subscription) -> None:
        """Stop a subscription at once (even mid-delivery); unsubscribing twice is harmless."""
        if not subscription.active:
            return
        subscription.active = False
        bucket = self._index[subscription._key]
        bucket.remove(subscription)
        if not bucket:
            del self._index[subscription._key]

    def _deliver(self, *changes: tuple[EventKind, Node, Node, Node, str]) -> None:
        """Queue events and, unless already delivering, deliver the queue (FIFO).

        A failing callback does not keep the other subscribers from their
        events (they would drift from the facts); the first error is raised
        once the queue is empty, and any further ones are logged.
        """
        self._queue.extend(changes)
        if self._delivering:
            return
        self._delivering = True
        errors: list[Exception] = []
        try:
            while self._queue:
                kind, s, p, o, perspective = self._queue.popleft()
                event = None
                for subscription in self._candidates(s, p):
                    wanted = subscription._object
                    if not (subscription.active
                            and (subscription.kind is None or subscription.kind == kind)
                            and (wanted is None or wanted is o or wanted == o)
                            and (subscription.perspective is None
                                 or subscription.perspective == perspective)):
                        continue
                    if event is None:
                        event = FactEvent(kind, self.name(s), self.name(p), self.name(o),
                                          perspective)
                    try:
                        subscription.callback(event)
                    except Exception as err:
                        if errors:
                            log.error("fact subscriber failed on %s", event, exc_info=err)
                        errors.append(err)
        finally:
            # Empty unless delivery was interrupted (KeyboardInterrupt …): stale
            # events must not surface later, after some unrelated change.
            self._queue.clear()
            self._delivering = False
        if errors:
            raise errors[0]

    def _candidates(self, s: Node, p: Node) -> list[Subscription]:
        """The subscriptions whose subject and predicate match, in subscription order.

        A copy: callbacks may subscribe and unsubscribe while it is walked.
        """
        index = self._index
        if not index:
            return []
        exact = index.get((s, p))
        by_predicate = index.get((None, p))
        by_subject = index.get((s, None))
        anything = index.get((None, None))
        if not (by_predicate or by_subject or anything):
            return list(exact) if exact else []
        buckets = [b for b in (exact, by_predicate, by_subject, anything) if b]
        if len(buckets) == 1:
            return list(buckets[0])
        return sorted((sub for bucket in buckets for sub in bucket), key=lambda sub: sub._order)

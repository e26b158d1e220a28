"""A perspective's facts kept in an index of our own, in front of its rdflib graph.

The fact database (:mod:`shary.facts.database`) keeps one of these per perspective (an
agent's beliefs) and one for the a-priori graph.  It is its own module because
it changes for its own reason: how facts are *stored* is a matter of speed
(measured in ``docs/architecture.md``), while the database's rules (what a name
means, which perspective a change goes to, the order events are delivered in)
are the engine's semantics and do not move when the store does.

Why an index: rdflib's store costs about 10 µs per change (a named graph's
contexts and indexes, ``len`` before and after), a good part of the whole path
from a perception change to the arm stopping.  So a perspective keeps the set
of its triples and the objects of each (subject, predicate), which answers
``holds``, ``objects``, ``triples`` and tells whether a change changes
anything; the rdflib graph stays the store for SPARQL and export, filled when
first read and then receiving the net changes made since its last read just
before it is read (:meth:`Perspective.sync`).

It also keeps the structures consumers derive from its facts
(:meth:`shary.facts.database.FactDatabase.derived`) current: each change is told to the
watchers of its predicate as it is made, before any event is delivered.
"""

from __future__ import annotations

import typing
from collections.abc import Callable

from rdflib import Graph
from rdflib.term import Node

from shary.facts.turtle import Triple

__all__ = ["Perspective"]


class Perspective:
    """One perspective's facts: an index in front of its rdflib graph (see the module's
    documentation).

    ``triples`` and ``objects`` are always current.  The rdflib graph is
    filled from them the first time someone reads it (:meth:`sync`: a file
    loaded only to be checked, or a world nobody queries with SPARQL, never
    pays for rdflib's store); from then on it lags behind by the changes in
    ``pending`` (each triple's last word: True added, False removed).
    """

    __slots__ = ("graph", "built", "triples", "objects", "pending", "derived", "watchers")

    def __init__(self, graph: Graph, source: Perspective | None = None):
        self.graph = graph
        self.built = False
        self.pending: dict[Triple, bool] = {}
        self.derived: dict[typing.Hashable, object] = {}
        """Structures derived from these triples (``FactDatabase.derived``), by key."""
        self.watchers: dict[Node, list[Callable[[bool, Triple], object]]] = {}
        """What keeps each derived structure current, by the predicates it follows."""
        if source is None:
            self.triples: set[Triple] = set()
            self.objects: dict[tuple[Node, Node], set[Node]] = {}
        else:
            self.triples = set(source.triples)
            self.objects = {key: set(objects) for key, objects in source.objects.items()}

    def add(self, triple: Triple) -> bool:
        """Add a triple; False when it was already there."""
        if triple in self.triples:
            return False
        self.triples.add(triple)
        key = (triple[0], triple[1])
        objects = self.objects.get(key)
        if objects is None:
            self.objects[key] = {triple[2]}
        else:
            objects.add(triple[2])
        if self.built:
            self.pending[triple] = True
        if self.watchers:
            for watcher in self.watchers.get(triple[1], ()):
                watcher(True, triple)
        return True

    def remove(self, triple: Triple) -> bool:
        """Remove a triple; False when it was not there."""
        if triple not in self.triples:
            return False
        self.triples.discard(triple)
        key = (triple[0], triple[1])
        objects = self.objects[key]
        objects.discard(triple[2])
        if not objects:
            del self.objects[key]
        if self.built:
            self.pending[triple] = False
        if self.watchers:
            for watcher in self.watchers.get(triple[1], ()):
                watcher(False, triple)
        return True

    def load(self, triples: set[Triple]) -> None:
        """Take in parsed triples (loading is setting up knowledge, not a change)."""
        new = triples - self.triples
        self.triples |= new
        objects = self.objects
        for s, p, o in new:
            found = objects.get((s, p))
            if found is None:
                objects[(s, p)] = {o}
            else:
                found.add(o)
        if self.built:
            self.pending.update(dict.fromkeys(new, True))
        if new:  # derived structures are rebuilt when next asked for: loading is rare
            self.derived.clear()
            self.watchers.clear()

    def sync(self) -> Graph:
        """Bring the rdflib graph up to date and return it."""
        graph = self.graph
        if not self.built:
            graph.addN((s, p, o, graph) for s, p, o in self.triples)
            self.built = True
        elif self.pending:
            for triple, present in self.pending.items():
                if present:
                    graph.add(triple)
                else:
                    graph.remove(triple)
        self.pending.clear()
        return graph

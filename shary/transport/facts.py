"""Fact changes an agent shares: how one process's facts reach the fact bases of others.

An agent that perceives (the world: poses, panels mounted, the verdict an
inspection read) keeps its own :class:`~shary.facts.database.FactDatabase`; agents in
other processes that reason on those facts (a robot's recipes, the spatial
reasoner, the Resource Manager's distances) keep theirs.  The sharer holds a
:class:`FactSharing`: an agent asks for the facts with a ``SUBSCRIBE`` act,
gets every fact of the perspective at once (so an agent that joins late, or
restarts, starts from the current state), then each change as a
:class:`~shary.transport.messages.FactChange`.  Changes are gathered while a
callback runs and sent when it returns (one message per callback, not one per
fact), *before* whatever the callback queued next: an inspection's verdict
reaches the robot before the inspection's outcome does.

The receiver applies a ``FactChange`` with :func:`apply_change`: removals,
then additions, each through the database's own methods, so its subscribers
(monitors, the team's positions) hear them as events.

Objects travel as JSON: names, numbers and booleans (what the database reads
back as itself); other literals (strings, dates) and blank nodes are not
shared, and subjects and predicates are always names.
"""

from __future__ import annotations

from typing import Any

from shary.transport.messages import FactChange
from shary.transport.port import MessagePort

SUBSCRIBE = "SUBSCRIBE"
"""The act by which an agent asks another for its facts."""

Triple = tuple[str, str, Any]


def _shareable(value: Any) -> bool:
    return isinstance(value, (str, int, float, bool))


class FactSharing:
    """Shares one perspective of ``facts`` with the agents that subscribed."""

    def __init__(self, facts: Any, port: MessagePort, sender: str,
                 perspective: str = "robot"):
        self.facts = facts
        self.port = port
        self.sender = sender
        self.perspective = perspective
        self.subscribers: list[str] = []
        self._changes: dict[Triple, bool] = {}
        """Triple -> added (True) or removed (False), the last word of this callback."""
        facts.subscribe(self._changed, perspective=perspective)

    def subscribe(self, address: str) -> None:
        """Send ``address`` every fact now, and every change from now on."""
        self.flush()
        if address not in self.subscribers:
            self.subscribers.append(address)
        triples = tuple(t for t in self.facts.triples(self.perspective)
                        if all(map(_shareable, t)))
        self.port.send(FactChange(self.sender, address, added=triples,
                                  perspective=self.perspective))

    def _changed(self, event: Any) -> None:
        if not self.subscribers:
            return
        triple = (event.subject, event.predicate, event.object)
        if not all(map(_shareable, triple)):
            return
        if not self._changes:
            self.port.loop.call_soon(self.flush)
        self._changes[triple] = event.kind == "added"

    def flush(self) -> None:
        """Send what changed since the last flush to every subscriber."""
        changes, self._changes = self._changes, {}
        if not changes or not self.subscribers:
            return
        added = tuple(t for t, new in changes.items() if new)
        removed = tuple(t for t, new in changes.items() if not new)
        for address in self.subscribers:
            self.port.send(FactChange(self.sender, address, added=added, removed=removed,
                                      perspective=self.perspective))


def apply_change(facts: Any, change: FactChange) -> None:
    """Apply a shared change to ``facts``: its removals, then its additions."""
    for s, p, o in change.removed:
        facts.remove(s, p, o, change.perspective)
    for s, p, o in change.added:
        facts.add(s, p, o, change.perspective)

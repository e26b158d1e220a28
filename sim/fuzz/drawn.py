"""A key a campaign draws (:class:`Drawn`), and the story that tells them (:class:`Story`).

A behaviour drawn for a run (:mod:`sim.fuzz.behaviours`) is a scenario document
with some keys changed; each is kept with what the run's story says of it,
where it is in the documents, what replaces it when it is taken away, and when
its moment comes, so that :mod:`sim.fuzz.keys` can run the scenario again
without it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["Drawn", "Story", "Where"]

Where = tuple["str | int", ...]
"""A place in a variation's documents: ``("scenario", key, …)`` or ``("team", key, …)``
(list items by index), or ``("kill",)`` for :attr:`Variation.kill`."""


@dataclass(frozen=True)
class Drawn:
    """One key a campaign drew: what the run's story says of it and where it is.

    Taking it away (:meth:`Variation.without`) must change the run: the
    ``keys-matter`` invariant (:mod:`sim.fuzz.keys`) checks it, so a key that the
    simulation ignores, or one drawn equal to what the person does anyway, is found
    rather than reported as tested."""

    says: str
    where: tuple[Where, ...]
    """The places it takes in the documents (a group of script steps takes several)."""
    rest: bool = False
    """A list item whose removal also removes the items after it: the k-th answer to
    an act (and later ones) is taken away, so the person does what they do unasked."""
    cue: tuple[Any, ...] = ()
    """When its moment comes, as :func:`sim.fuzz.keys.reached` reads it from the rows
    (empty: from the start): an answer to the third ASK-TASK has none in a run where
    the robot asked once."""
    unasked: Any = None
    """What takes its place when it is taken away (None: nothing, the reader's default):
    a first answer drawn gives way to the base profile's own answer to that act."""


class Story:
    """The behaviour drawn, told in a few words, and the keys it drew (:class:`Drawn`)."""

    def __init__(self, *parts: str) -> None:
        self.parts = list(parts)
        self.keys: list[Drawn] = []

    def __call__(self, says: str, *where: Where, rest: bool = False,
                 cue: tuple[Any, ...] = (), unasked: Any = None) -> None:
        self.parts.append(says)
        if where:
            self.keys.append(Drawn(says, where, rest, cue, unasked))



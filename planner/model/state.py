"""Search states: copy-on-write attribute values, and for HDDL an index of the facts.

:class:`State` maps (entity, attribute) to a value: a base shared by many
states plus this state's own changes, folded into a new base beyond
:data:`FOLD` changes (the search makes a state per action, and most of the
world stays as it was).

HDDL methods leave variables free (Blocksworld's ``m7_do_clear ?x ?y`` with
``(on ?y ?x)``): trying every object of the variable's type for each of them
makes a 1,000-block problem a million checks per decomposition.  A binder
(:mod:`planner.search.binding`) instead asks the state for the facts that match a
pattern -- ``on`` with argument 1 equal to ``b7`` -- and tries only those.

A fact is the state key ``(predicate, args)``; its value is True while it
holds and None once deleted.  :class:`FactState` is the search's
copy-on-write :class:`State` plus, for each *pattern* the
binders use (a predicate and the argument positions they know), buckets from
the known values to the matching argument tuples.  The buckets are copied on
write like the values: a state shares its parent's buckets until it changes a
fact in one of them.  A bucket is a dict used as an insertion-ordered set, so
that the order the binders try facts in is the same on every run (a set's
order would follow string hashing, which changes between runs).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

FOLD = 64
"""A state's own changes are folded into a new base beyond this many."""

Bucket = dict[tuple[str, ...], None]
BucketKey = tuple[str, tuple[int, ...], tuple[str, ...]]
Patterns = Mapping[str, tuple[tuple[int, ...], ...]]

FLAT = 128
"""A state of at most this many values is kept whole in its own changes (``delta``; its
base is empty): one copy a child, one dict to read (the search reads more than it
writes)."""

_EMPTY: Bucket = {}
_FLAT: dict = {}
"""The base of every flat state: never written (a state writes to its ``delta``)."""
_MISSING = object()


class State:
    """Attribute values: a base shared by many states plus this state's own changes."""

    __slots__ = ("base", "delta")

    def __init__(self, base: dict[tuple[str, Any], Any], delta: dict | None = None):
        self.base = base
        self.delta = delta if delta is not None else {}

    def get(self, entity: str, attribute: Any) -> Any:
        key = (entity, attribute)
        value = self.delta.get(key, _MISSING)
        return self.base.get(key) if value is _MISSING else value

    def child(self) -> State:
        base, delta = self.base, self.delta
        if base:
            if len(delta) > FOLD or len(base) <= FLAT:
                merged = {**base, **delta}
                return State(merged) if len(merged) > FLAT else State(_FLAT, merged)
        elif len(delta) > FLAT:  # grown out of flat
            return State(dict(delta))
        return State(base, dict(delta))

    def set(self, entity: str, attribute: Any, value: Any) -> None:
        self.delta[(entity, attribute)] = value

    def items(self) -> dict[tuple[str, Any], Any]:
        return {**self.base, **self.delta}


class FactState(State):
    """A :class:`State` whose true facts are also indexed by ``patterns``."""

    __slots__ = ("patterns", "ibase", "idelta", "owned")

    def __init__(self, base: dict[tuple[str, Any], Any], patterns: Patterns,
                 delta: dict | None = None, ibase: dict[BucketKey, Bucket] | None = None,
                 idelta: dict[BucketKey, Bucket] | None = None):
        self.base = base
        self.delta = delta if delta is not None else {}
        self.patterns = patterns
        if ibase is None:
            ibase = {}
            for (pred, args), value in base.items():
                if value:
                    for positions in patterns.get(pred, ()):
                        key = (pred, positions, tuple(args[i] for i in positions))
                        ibase.setdefault(key, {})[args] = None
        self.ibase = ibase
        self.idelta = idelta if idelta is not None else {}
        self.owned: set[BucketKey] = set()
        """The buckets of ``idelta`` this state copied (the others are its parent's)."""

    def child(self) -> FactState:
        if len(self.delta) > FOLD:
            return FactState({**self.base, **self.delta}, self.patterns, None,
                             {**self.ibase, **self.idelta})
        return FactState(self.base, self.patterns, dict(self.delta), self.ibase,
                         dict(self.idelta))

    def set(self, entity: str, attribute: Any, value: Any) -> None:
        key = (entity, attribute)
        delta = self.delta
        shapes = self.patterns.get(entity)
        if not shapes:  # a predicate no binder looks up
            delta[key] = value
            return
        old = delta.get(key, _MISSING)
        if old is _MISSING:
            old = self.base.get(key)
        delta[key] = value
        if bool(old) == bool(value):
            return
        for positions in shapes:
            bucket = self._own((entity, positions, tuple(attribute[i] for i in positions)))
            if value:
                bucket[attribute] = None
            else:
                bucket.pop(attribute, None)

    def _own(self, key: BucketKey) -> Bucket:
        """This state's own copy of a bucket, made on its first write."""
        if key in self.owned:
            return self.idelta[key]
        shared = self.idelta.get(key, _MISSING)
        if shared is _MISSING:
            shared = self.ibase.get(key, _EMPTY)
        bucket = dict(shared)
        self.idelta[key] = bucket
        self.owned.add(key)
        return bucket

    def matching(self, pred: str, positions: tuple[int, ...],
                 values: tuple[str, ...]) -> Bucket:
        """The argument tuples of the true ``pred`` facts whose arguments at ``positions``
        are ``values`` (``positions`` must be one of the predicate's patterns).  Read it
        without changing this state: the search never changes a state that has children."""
        key = (pred, positions, values)
        bucket = self.idelta.get(key, _MISSING)
        if bucket is _MISSING:
            return self.ibase.get(key, _EMPTY)
        return bucket  # type: ignore[return-value]

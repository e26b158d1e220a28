"""Referring expressions: a description that singles an object out for one listener.

"If the robot wants to talk about a green cube on a table but another green
one is on a close shelf and a red cube is on the table, how can it do?"
(JAHRVIS, Section VI-E).  It says "the green cube on the table": the fewest
properties that tell the target from everything else *the listener* knows
of, read from the listener's perspective of the fact base.

The algorithm is Dale & Reiter's incremental algorithm (1995), extended with
relations as Dale & Haddock (1991) and Krahmer & van Deemter's survey (2012)
describe: the attributes are tried in a preference order (type, colour, size
by default; :class:`Referrer` takes another order), each kept when it rules
out a distractor; the type is always kept, as the head noun.  When the
attributes leave distractors, the target's relations (on, in, near, left of
…) to landmarks are tried, each landmark described in turn by the same
algorithm (to a bounded depth, never through the target again).  The result
is checked by evaluating it again over the whole perspective; a description
that does not denote exactly the target is never returned: the referrer then
says so (:attr:`Description.pointing`) and the speaker points at the object
("this cube", with a ``point-at`` gesture).

Nothing here runs SPARQL: a :class:`PerspectiveIndex` is built once from the
perspective's triples (each attribute value's set of things, each relation's
things per landmark) and then kept current by the fact database as facts
change (:meth:`shary.facts.database.FactDatabase.derived`), so that a sentence costs
what it says, not the size of the world; describing an object is a few set
intersections.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from shary.dialogue.verbalize import humanize, plural

__all__ = ["AGENT_PHRASES", "AGENT_TYPES", "ATTRIBUTES", "INVERSES", "RELATIONS", "Description",
           "PerspectiveIndex", "Referrer"]

ATTRIBUTES = ("type", "color", "size")
"""The attributes tried, in Dale & Reiter's preference order, unless told otherwise."""

RELATIONS: Mapping[str, str] = {
    "isOn": "on", "isIn": "in", "heldBy": "held by", "isUnder": "under", "isNear": "near",
    "leftOf": "to the left of", "rightOf": "to the right of",
    "behind": "behind", "inFrontOf": "in front of",
}
"""Spatial relations (predicate -> preposition), in the order they are tried."""

INVERSES: Mapping[str, str] = {"isHolding": "heldBy"}
"""Facts whose subject is the landmark, indexed the other way round: (alice,
isHolding, cup) is (cup, heldBy, alice), "the cup in Alice's hand"."""

AGENT_PHRASES: Mapping[str, str] = {
    "heldBy": "in {my} hand", "leftOf": "on {my} left", "rightOf": "on {my} right",
}
"""How a relation to a person or robot is said, from their point of view: "the
placement on your left", "the cube in my hand" (``{my}`` is the possessive: my,
your, Alice's); other relations put the name after the preposition ("near you")."""

AGENT_TYPES = frozenset({"Human", "Robot", "Agent", "Person"})
"""Types of agents: an agent is named ("Alice"), never described."""

_ADJECTIVE_ORDER = {"size": 0, "color": 2}
"""English puts size before colour ("the small green cube"); other attributes in between."""

_LABEL = "rdfs:label"


@dataclass(frozen=True)
class Description:
    """What is said to pick out ``target``: its head noun, attributes and relations.

    ``attributes`` are (predicate, value) pairs; ``relations`` are
    (predicate, preposition, landmark's description); ``pointing`` is True
    when no description singles the target out (say "this …" and point).
    ``name`` is set for things referred to by a proper name (agents).
    """

    target: str
    noun: str
    attributes: tuple[tuple[str, str], ...] = ()
    relations: tuple[tuple[str, str, Description], ...] = ()
    pointing: bool = False
    name: str | None = None
    given: tuple[tuple[str, str], ...] = ()
    """Attributes the listener already said: left out after "one" ("the one on the shelf")."""
    silent: tuple[tuple[str, str], ...] = ()
    """(predicate, landmark) relations that tell the target apart but go unsaid: the
    sentence around the description says them ("I placed the blue cube on the stick")."""

    @property
    def gesture(self) -> tuple[str, str] | None:
        """The gesture that goes with the words: ``("point-at", target)`` or None."""
        return ("point-at", self.target) if self.pointing else None

    @property
    def relation_count(self) -> int:
        """Relations used, the landmarks' own included (what the benchmark reports)."""
        return sum(1 + d.relation_count for _, _, d in self.relations)

    def text(self, head: str | None = None, people: Mapping[str, str] | None = None) -> str:
        """The noun phrase: "the small green cube on the table" (``head="one"`` gives
        "the one on the table", as the second half of a disambiguation question).

        ``people`` maps the speaker and the addressee to "me" and "you", so that
        a landmark that is one of them reads "near you", "on my left".
        """
        people = people or {}
        if self.name is not None:
            return people.get(self.target, self.name)
        if self.pointing:
            return f"this {self.noun}"
        adjectives = sorted((a for a in self.attributes if a[0] != "type"
                             and (head is None or a not in self.given)),
                            key=lambda a: _ADJECTIVE_ORDER.get(a[0], 1))
        words = [humanize(v) for _, v in adjectives] + [head or self.noun]
        for predicate, preposition, landmark in self.relations:
            phrase = AGENT_PHRASES.get(predicate) if landmark.name is not None else None
            if phrase is not None:
                words.append(phrase.format(my=_possessive(landmark.text(people=people))))
            else:
                words += [preposition, landmark.text(people=people)]
        return "the " + " ".join(words)

    def __str__(self) -> str:
        return self.text()


def _possessive(name: str) -> str:
    """"me" -> "my", "you" -> "your", "Alice" -> "Alice's"."""
    return {"me": "my", "you": "your"}.get(name, name + "'s")


@dataclass
class PerspectiveIndex:
    """One perspective's facts indexed for describing things (see the module's docstring).

    ``entities`` are the things with a type; ``values[thing][attribute]``
    their attribute values; ``having[attribute][value]`` the things with that
    value; ``related[predicate][landmark]`` the things in that relation to
    the landmark; ``relations[thing]`` its (predicate, landmark) pairs in the
    order relations are tried; ``labels`` the rdfs:label of classes and things.
    """

    entities: set[str] = field(default_factory=set)
    values: dict[str, dict[str, set[str]]] = field(default_factory=dict)
    having: dict[str, dict[str, set[str]]] = field(default_factory=dict)
    related: dict[str, dict[str, set[str]]] = field(default_factory=dict)
    relations: dict[str, list[tuple[str, str]]] = field(default_factory=dict)
    labels: dict[str, str] = field(default_factory=dict)

    rank: dict[str, int] = field(default_factory=lambda: {p: i for i, p in enumerate(RELATIONS)})
    """The relations indexed, each with its place in the order they are tried."""
    wanted: frozenset[str] = frozenset(ATTRIBUTES) | {"type"}
    """The attributes indexed."""

    @classmethod
    def from_triples(cls, triples: Iterable[tuple[object, object, object]],
                     attributes: Sequence[str] = ATTRIBUTES,
                     relations: Mapping[str, str] = RELATIONS) -> PerspectiveIndex:
        """Index (subject, predicate, object) names: what :meth:`FactDatabase.triples` gives."""
        index = cls(rank={p: i for i, p in enumerate(relations)},
                    wanted=frozenset(attributes) | {"type"})
        for s, p, o in triples:
            index.change(True, s, p, o)
        return index

    @classmethod
    def from_facts(cls, facts: Any, perspective: str,
                   attributes: Sequence[str] = ATTRIBUTES,
                   relations: Mapping[str, str] = RELATIONS) -> PerspectiveIndex:
        """The index of one perspective of a :class:`shary.facts.database.FactDatabase`, kept
        current by the database as facts change (built on the first call only: a
        sentence costs what it says, not the size of the world)."""
        attributes, relations = tuple(attributes), dict(relations)
        return facts.derived(
            (cls, attributes, tuple(relations)), perspective,
            lambda triples: cls.from_triples(triples, attributes, relations),
            {*attributes, "type", *relations, *INVERSES, _LABEL}, PerspectiveIndex.change)

    def change(self, added: bool, s: object, p: object, o: object) -> None:
        """Take in one fact added (``added``) or removed; facts of other predicates are
        ignored."""
        s, p, o = str(s), str(p), str(o)
        if p in INVERSES:
            s, p, o = o, INVERSES[p], s
        if p in self.wanted:
            if added:
                self.values.setdefault(s, {}).setdefault(p, set()).add(o)
                self.having.setdefault(p, {}).setdefault(o, set()).add(s)
                if p == "type":
                    self.entities.add(s)
                return
            _discard(self.values.get(s), p, o)
            _discard(self.having.get(p), o, s)
            if p == "type" and not self.values.get(s, {}).get("type"):
                self.entities.discard(s)
        elif p in self.rank:
            pairs = self.relations.setdefault(s, [])
            if added:
                _add(self.related.setdefault(p, {}), o, s)
                if (p, o) not in pairs:
                    pairs.append((p, o))
                    pairs.sort(key=lambda pair: (self.rank[pair[0]], pair[1]))
                return
            _discard(self.related.get(p), o, s)
            if (p, o) in pairs:
                pairs.remove((p, o))
            if not pairs:
                del self.relations[s]
        elif p == _LABEL:
            if added:
                self.labels[s] = o
            elif self.labels.get(s) == o:
                del self.labels[s]


def _add(sets: dict[str, set[str]], key: str, item: str) -> None:
    found = sets.get(key)
    if found is None:
        sets[key] = {item}
    else:
        found.add(item)


def _discard(sets: dict[str, set[str]] | None, key: str, item: str) -> None:
    """Take ``item`` out of ``sets[key]``, and the key with its last item."""
    found = sets.get(key) if sets is not None else None
    if found is not None:
        found.discard(item)
        if not found:
            del sets[key]  # type: ignore[index]


class Referrer:
    """Describes things for one listener, from an index of the listener's perspective.

    ``attributes`` is the preference order of the incremental algorithm;
    ``relations`` the spatial relations tried (predicate -> preposition),
    in order; ``depth`` how deep landmarks may be described in turn.
    """

    def __init__(self, index: PerspectiveIndex, attributes: Sequence[str] = ATTRIBUTES,
                 relations: Mapping[str, str] = RELATIONS, depth: int = 2):
        self.index = index
        self.attributes = tuple(a for a in attributes if a != "type")
        self.relations = dict(relations)
        self.depth = depth

    @classmethod
    def for_perspective(cls, facts: Any, perspective: str,
                        attributes: Sequence[str] = ATTRIBUTES,
                        relations: Mapping[str, str] = RELATIONS) -> Referrer:
        """A referrer over one perspective of a fact database (its index is kept current
        by the database: see :meth:`PerspectiveIndex.from_facts`)."""
        return cls(PerspectiveIndex.from_facts(facts, perspective, attributes, relations),
                   attributes, relations)

    # -- words -----------------------------------------------------------------------------------

    def _kind(self, types: set[str]) -> str:
        """The most specific of a thing's types: the one fewest things have (a Bottle
        rather than an Object)."""
        having = self.index.having["type"]
        return min(types, key=lambda t: (len(having[t]), t))

    def noun(self, thing: str) -> str:
        """The head noun: the type's label, or the type's name in words ("coffee table")."""
        types = self.index.values.get(thing, {}).get("type")
        if not types:
            return "thing"
        kind = self._kind(types)
        return self.index.labels.get(kind, humanize(kind))

    def knows(self, thing: str) -> bool:
        """Whether this perspective holds anything of ``thing`` (its type, at least)."""
        return bool(self.index.values.get(thing, {}).get("type"))

    def is_agent(self, thing: str) -> bool:
        return bool(self.index.values.get(thing, {}).get("type", set()) & AGENT_TYPES)

    def text(self, thing: str) -> str:
        """The noun phrase for ``thing`` (what a :class:`Verbalizer` calls ``refer``)."""
        return self.describe(thing).text()

    # -- the algorithm ---------------------------------------------------------------------------

    def describe(self, target: str, context: Iterable[str] | None = None,
                 given: Iterable[tuple[str, str]] = (), by_name: bool = False,
                 implied: Iterable[str] = ()) -> Description:
        """The description of ``target`` that rules out every other thing of ``context``
        (every entity of the perspective, unless given).

        ``given`` are (attribute, value) pairs to say anyway (what the person
        already said: "the green cube on the table" rather than "the cube on
        the table").  ``implied`` are the other things the sentence names: the
        target's relations to them are said by the sentence itself, so they
        rule out distractors without being said twice ("I placed the blue
        cube on the stick", not "the blue cube on the stick on the stick").
        Returns a pointing description when nothing else works, or, with
        ``by_name``, words for a speaker who cannot point: its identifier in
        words if that is a name ("the coffee area" for ``coffee-area``), never
        with a number ("one of the red cubes" for ``red_cube_1``).
        """
        index = self.index
        if self.is_agent(target):
            return Description(target, self.noun(target),
                               name=index.labels.get(target) or humanize(target).title())
        scope = None if context is None else set(context)
        said = dict(given)
        found = self._describe(target, scope, said, self.depth, frozenset({target}),
                               frozenset(implied) - {target})
        if found is not None and self.denotes(found, scope) == {target}:
            return replace(found, given=tuple(a for a in found.attributes
                                              if said.get(a[0]) == a[1]))
        if by_name:
            return Description(target, self.noun(target), name=self._unnamed(target))
        return Description(target, self.noun(target), pointing=True)

    def _unnamed(self, target: str) -> str:
        """Words for a thing no description singles out, for a speaker who cannot point:
        its identifier in words when that is a name ("the coffee area"); for a thing
        numbered among its twins ("red_cube_1"), "one of the red cubes", or, if its
        type is not known, the identifier without the number ("the red cube")."""
        words = humanize(target).split()
        if not any(w.isdigit() for w in words):
            return "the " + " ".join(words)
        values = self.index.values.get(target, {})
        if not values.get("type"):
            return "the " + " ".join(w for w in words if not w.isdigit())
        adjectives = [humanize(min(values[a])) for a in sorted(
            (a for a in self.attributes if values.get(a)),
            key=lambda a: _ADJECTIVE_ORDER.get(a, 1))]
        return "one of the " + " ".join(adjectives + [plural(self.noun(target))])

    def _describe(self, target: str, scope: set[str] | None, given: dict[str, str],
                  depth: int, visited: frozenset[str],
                  implied: frozenset[str] = frozenset()) -> Description | None:
        index = self.index
        values = index.values.get(target, {})
        types = values.get("type")
        if not types:
            return None
        kind = self._kind(types)
        # The things that fit what is chosen so far, the target among them (it fits
        # all it is described by): the index's own set until narrowed, never copied,
        # so that describing a cube does not cost every cube of the world.
        fitting = index.having["type"][kind]
        if scope is not None:
            fitting = (fitting & scope) | {target}
        chosen: list[tuple[str, str]] = [("type", kind)]
        for attribute in self.attributes:
            have = values.get(attribute)
            if not have:
                continue
            value = given.get(attribute)
            if value not in have:
                # The value that rules out the most distractors (Dale & Reiter's
                # "FindBestValue" for an attribute with several values).
                value = min(have, key=lambda v: (len(fitting & index.having[attribute][v]), v))
            left = fitting & index.having[attribute][value]
            if len(left) < len(fitting) or attribute in given:
                chosen.append((attribute, value))
                fitting = left
        silent: list[tuple[str, str]] = []
        for predicate, landmark in index.relations.get(target, ()):
            if len(fitting) > 1 and landmark in implied:
                left = fitting & index.related[predicate][landmark]
                if len(left) < len(fitting):
                    silent.append((predicate, landmark))
                    fitting = left
        relations: list[tuple[str, str, Description]] = []
        if len(fitting) > 1 and depth > 0:
            for predicate, landmark in index.relations.get(target, ()):
                if landmark in visited or landmark in implied:
                    continue
                left = fitting & index.related[predicate][landmark]
                if len(left) == len(fitting):
                    continue
                described = self._landmark(landmark, depth - 1, visited | {target})
                if described is None:
                    continue
                relations.append((predicate, self.relations[predicate], described))
                fitting = left
                if len(fitting) == 1:
                    break
        if len(fitting) > 1:
            return None
        return Description(target, self.noun(target), tuple(chosen), tuple(relations),
                           silent=tuple(silent))

    def _landmark(self, landmark: str, depth: int, visited: frozenset[str]) -> Description | None:
        if self.is_agent(landmark):
            return Description(landmark, self.noun(landmark),
                               name=self.index.labels.get(landmark) or humanize(landmark).title())
        return self._describe(landmark, None, {}, depth, visited)

    def denotes(self, description: Description, scope: set[str] | None = None) -> set[str]:
        """The things of ``scope`` (every entity if None) that fit the description: the
        check that a description is never ambiguous."""
        if description.name is not None:
            return {description.target}
        if description.pointing:
            return {description.target}
        index = self.index
        sets: list[set[str]] = [] if scope is None else [scope]
        sets += [index.having.get(attribute, {}).get(value, set())
                 for attribute, value in description.attributes]
        sets += [index.related.get(predicate, {}).get(landmark, set())
                 for predicate, landmark in description.silent]
        for predicate, _, landmark in description.relations:
            near: set[str] = set()
            for thing in self.denotes(landmark):
                near |= index.related.get(predicate, {}).get(thing, set())
            sets.append(near)
        if not sets:
            return set(index.entities)
        # From the smallest set on, so that the check costs what the description picks
        # out rather than every thing of its type.
        sets.sort(key=len)
        return sets[0].intersection(*sets[1:])

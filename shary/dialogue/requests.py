"""Understanding requests: a person's sentence read with the grammar of action labels.

JAHRVIS's Communication Manager receives "Take the green cube", gets back the
action and a SPARQL query per parameter, asks the knowledge base for the
objects that match, and asks "Do you mean the green cube on the table or on
the shelf?" when more than one does (Section VI-E).  Here:

* the **grammar** is the action ontology's labels read backwards
  (``{Agent} @Place {Pickable} on {Support}`` reads "place the red cube on
  the stick"), plus a few phrasings people use for the same actions
  (:data:`PHRASINGS`: "take the cube", "give me the bottle");
* a sentence may start with "please", "can you", "could you" … (the robot is
  asked: a **request**) or with "I'll", "I will", "let me" (the person says
  they do it themselves: a **constraint** on the shared plan, as in "I'll
  take the bottle myself");
* each object parameter becomes a :class:`Query` (type, attributes,
  relations to landmarks, each a query in turn) that renders as SPARQL
  (:meth:`Query.sparql`) and is answered from the listener's
  :class:`~shary.dialogue.reg.PerspectiveIndex` (:meth:`Query.matches`), the
  same answer without a SPARQL engine per sentence;
* :func:`resolve` gives 0, 1 or several matches per parameter, with what the
  robot says: "I see no blue cube.", or the disambiguation question built
  from referring expressions among the candidates; :func:`interpret_answer`
  reads the answer ("the one on the table", "the red one", "the first").

A sentence with a word the grammar does not know, or that no label reads,
gives a :class:`Understanding` whose ``problem`` is a sentence for the
person ("I did not understand 'frobnicate'."), never an exception.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field

from shary.dialogue.reg import AGENT_TYPES, RELATIONS, Description, PerspectiveIndex, Referrer
from shary.dialogue.verbalize import Label, conjugate, humanize

__all__ = ["ACTIONS", "PHRASINGS", "Grammar", "Query", "Request", "Resolution", "Understanding",
           "interpret_answer", "resolve"]

ACTIONS = ("give-object", "fetch", "clean-up", "explore-place", "pick", "place", "dump",
           "put-back", "give")
"""The actions a request may name by default, tried in this order: the joint tasks first
("give me the bottle" is the give-object task), then the robot's actions."""

PHRASINGS: Mapping[str, Sequence[str]] = {
    "pick": ("{Agent} @Take {Pickable}", "{Agent} @Pick up {Pickable}",
             "{Agent} @Pick {Pickable} up", "{Agent} @Grab {Pickable}", "{Agent} @Get {Pickable}"),
    "place": ("{Agent} @Put {Pickable} on {Support}", "{Agent} @Put {Pickable} onto {Support}"),
    "dump": ("{Agent} @Put {Pickable} into {Support}", "{Agent} @Put {Pickable} in {Support}",
             "{Agent} @Throw {Pickable} into {Support}"),
    "give-object": ("{Agent} @Give {Partner} {Object}", "{Agent} @Bring {Partner} {Object}",
                    "{Agent} @Hand {Partner} {Object}", "{Agent} @Bring {Object} to {Partner}",
                    "{Agent} @Pass {Partner} {Object}"),
}
"""Other ways people say the ontology's actions (action name -> labels, same roles)."""

_ROBOT_DOES = (("can", "you"), ("could", "you"), ("would", "you"), ("will", "you"),
               ("please",), ("you",), ("kindly",))
_PERSON_DOES = (("i", "will"), ("i", "am", "going", "to"), ("let", "me"), ("i", "can"),
                ("i", "shall"), ("i", "want", "to"), ("i",))
_ENDINGS = (("please",), ("myself",), ("yourself",), ("for", "me"))
_DETERMINERS = frozenset({"the", "a", "an", "this", "that", "my", "your"})
_CONTRACTIONS = {"i'll": "i will", "i'm": "i am", "you'll": "you will", "let's": "let us",
                 "can't": "cannot", "don't": "do not"}
_ORDINALS = {"first": 0, "second": 1, "third": 2, "fourth": 3, "last": -1}
_WORDS = {**{c: ("color", c) for c in (
    "red", "green", "blue", "yellow", "white", "black", "brown", "orange", "pink", "purple",
    "grey", "gray")}, **{z: ("size", z) for z in ("small", "big", "large", "little", "tall")}}
"""Adjectives understood even when nothing in the perspective has them ("I see no blue cube")."""
_AGENT_ROLES = frozenset({"Agent", "Human", "Robot", "Person"})


def _words(text: str) -> list[str]:
    words = re.findall(r"[a-z0-9]+(?:['-][a-z0-9]+)*", text.lower().replace("’", "'"))
    return " ".join(_CONTRACTIONS.get(w, w) for w in words).split()


@dataclass(frozen=True)
class Query:
    """What a noun phrase asks for: a type, attribute values, relations to landmarks.

    ``name`` is set for a thing named directly (an agent, "it").  Render it
    as SPARQL with :meth:`sparql`; answer it from an index with :meth:`matches`.
    """

    type: str | None = None
    attributes: tuple[tuple[str, str], ...] = ()
    relations: tuple[tuple[str, Query], ...] = ()
    name: str | None = None
    words: str = ""

    def sparql(self, variable: str = "x") -> str:
        """A SPARQL SELECT of the things that match (prefix ``w:`` is the world's)."""
        lines: list[str] = []
        self._patterns(variable, lines, [0])
        return f"SELECT DISTINCT ?{variable} WHERE {{\n" + "".join(
            f"  {line}\n" for line in lines) + "}"

    def _patterns(self, variable: str, lines: list[str], counter: list[int]) -> None:
        if self.name is not None:
            lines.append(f"VALUES ?{variable} {{ w:{self.name} }}")
            return
        lines.append(f"?{variable} w:type " + (f"w:{self.type} ." if self.type else "?any ."))
        for attribute, value in self.attributes:
            lines.append(f"?{variable} w:{attribute} w:{value} .")
        for predicate, landmark in self.relations:
            counter[0] += 1
            other = f"l{counter[0]}"
            lines.append(f"?{variable} w:{predicate} ?{other} .")
            landmark._patterns(other, lines, counter)

    def matches(self, index: PerspectiveIndex, among: Iterable[str] | None = None) -> list[str]:
        """The things of the index (of ``among``, if given) that fit, sorted."""
        if self.name is not None:
            found = {self.name}
        else:
            found = set(index.having.get("type", {}).get(self.type, ())) if self.type \
                else set(index.entities)
            for attribute, value in self.attributes:
                found &= index.having.get(attribute, {}).get(value, set())
            for predicate, landmark in self.relations:
                near: set[str] = set()
                for thing in landmark.matches(index):
                    near |= index.related.get(predicate, {}).get(thing, set())
                found &= near
        if among is not None:
            found &= set(among)
        return sorted(found)


@dataclass(frozen=True)
class Request:
    """A sentence understood: who should do which action, with a query per parameter.

    ``kind`` is "request" (the addressee is asked to act) or "constraint"
    (the speaker says they will do it: a constraint on the shared plan).
    ``params`` maps each role of the label to a :class:`Query`, agents
    included (as named queries); ``roles`` lists them in the action's order.
    """

    kind: str
    action: str
    agent: str
    roles: tuple[str, ...]
    params: Mapping[str, Query]
    label: str
    sentence: str


@dataclass(frozen=True)
class Understanding:
    """What :meth:`Grammar.parse` made of a sentence: a request, or a problem to say."""

    request: Request | None = None
    problem: str | None = None


@dataclass(frozen=True)
class Resolution:
    """The matches of each parameter, and what to say about them.

    ``status`` is "none" (some parameter matches nothing: ``message`` says
    so), "several" (``question`` asks which one; ``role`` and ``candidates``
    are what it asks about) or "one" (``bindings`` holds every parameter's
    thing).  ``gestures`` are the pointing gestures the question needs.
    """

    status: str
    matches: Mapping[str, list[str]]
    bindings: Mapping[str, str] = field(default_factory=dict)
    message: str | None = None
    question: str | None = None
    role: str | None = None
    candidates: tuple[str, ...] = ()
    descriptions: tuple[Description, ...] = ()
    gestures: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class _Form:
    action: str
    label: Label
    classes: Mapping[str, str]
    """Role -> the class of what fills it (agents are named, not described), in the
    action's order of parameters."""


class Grammar:
    """The sentences the robot understands: one form per action label (and phrasing).

    ``forms`` are (action name, label, role classes); the vocabulary of
    nouns and adjectives comes from the listener's index when parsing.
    """

    def __init__(self, forms: Iterable[tuple[str, str, Mapping[str, str]]]):
        self.forms = [_Form(action, Label.parse(label), dict(classes))
                      for action, label, classes in forms]
        self.verbs = {form.label.parts[0][1].split()[0] for form in self.forms}
        self.words = {w for form in self.forms for kind, text in form.label.parts
                      if kind != "slot" for w in text.split()}

    @classmethod
    def from_ontology(cls, ontology: object, actions: Iterable[str] = ACTIONS,
                      phrasings: Mapping[str, Sequence[str]] = PHRASINGS) -> Grammar:
        """The forms of the named ``actions`` (tried in that order): each one's label in
        the action ontology, then its other phrasings."""
        forms: list[tuple[str, str, Mapping[str, str]]] = []
        for action in actions:
            cls_name = ontology.action_class(action)  # type: ignore[attr-defined]
            if cls_name is None:
                continue
            classes = {p.role: p.role_class
                       for p in ontology.parameters(cls_name)}  # type: ignore[attr-defined]
            label = ontology.label(cls_name)  # type: ignore[attr-defined]
            forms += [(action, text, classes)
                      for text in ([label] if label else []) + list(phrasings.get(action, ()))]
        return cls(forms)

    # -- parsing ---------------------------------------------------------------------------------

    def parse(self, sentence: str, index: PerspectiveIndex, *, speaker: str, addressee: str,
              it: str | None = None) -> Understanding:
        """Read ``sentence`` said by ``speaker`` to ``addressee``; ``it`` is what "it" means."""
        words = _words(sentence)
        if not words:
            return Understanding(problem="I did not hear a request.")
        agent, kind, words = addressee, "request", list(words)
        for prefixes, who, what in ((_ROBOT_DOES, addressee, "request"),
                                    (_PERSON_DOES, speaker, "constraint")):
            found = next((p for p in prefixes if tuple(words[:len(p)]) == p
                          and len(words) > len(p)), None)
            if found:
                agent, kind, words = who, what, words[len(found):]
                break
        while words[:1] == ["please"]:
            words = words[1:]
        for ending in _ENDINGS:
            if tuple(words[-len(ending):]) == ending and len(words) > len(ending):
                words = words[:-len(ending)]
        nps = _NounPhrases(index, speaker, addressee, it)
        for form in self.forms:
            readings = list(self._read(form, words, nps))
            if readings:
                # Of the ways to split the words among the parameters ("put the cube on
                # the table on the shelf"), the first whose every query finds something.
                params = next((r for r in readings
                               if all(q.matches(index) for q in r.values())), readings[0])
                params[form.label.agent] = Query(name=agent, words=agent)
                roles = (form.label.agent, *form.classes) if form.classes else form.label.params
                return Understanding(Request(kind, form.action, agent, tuple(roles),
                                             params, form.label.text, sentence))
        unknown = next((w for w in words if not self._known(w, nps)), None)
        if unknown is not None:
            return Understanding(problem=f"I did not understand '{unknown}'.")
        if "it" in words and it is None:
            return Understanding(problem="I do not know what 'it' is; please name the object.")
        if words[0] in self.verbs:
            return Understanding(problem=f"I did not understand what to {words[0]} in "
                                         f"'{sentence.strip()}'.")
        if not any(w in self.verbs or conjugate(w, "VB") in self.verbs for w in words[:2]):
            return Understanding(problem=f"I did not understand what to do in "
                                         f"'{sentence.strip()}'.")
        return Understanding(problem=f"I did not understand '{sentence.strip()}'; I understand "
                                     "requests such as 'take the green cube' or 'give me the "
                                     "bottle'.")

    def _known(self, word: str, nps: _NounPhrases) -> bool:
        return (word in self.words or word in nps.vocabulary or word in _DETERMINERS
                or word in {"it", "me", "you", "one", "myself", "yourself", "please"})

    def _read(self, form: _Form, words: list[str],
              nps: _NounPhrases) -> Iterator[dict[str, Query]]:
        """Every reading of ``words`` as the form's parameters (none: the form does not fit)."""
        parts = form.label.parts
        verb = parts[0][1].split()
        if words[:len(verb)] == verb:
            yield from self._match(form, list(parts[1:]), words[len(verb):], nps, {})

    def _match(self, form: _Form, parts: list[tuple[str, str]], words: list[str],
               nps: _NounPhrases, bound: dict[str, Query]) -> Iterator[dict[str, Query]]:
        if not parts:
            if not words:
                yield dict(bound)
            return
        (kind, text), rest = parts[0], parts[1:]
        if kind == "word":
            expected = text.lower().split()
            if words[:len(expected)] == expected:
                yield from self._match(form, rest, words[len(expected):], nps, bound)
            return
        agentive = form.classes.get(text, "") in _AGENT_ROLES
        # Shorter spans first: "put the cube on the table" reads the cube, then the table.
        for end in range(1, len(words) + 1):
            query = nps.read(words[:end], agentive)
            if query is not None:
                yield from self._match(form, rest, words[end:], nps, {**bound, text: query})


class _NounPhrases:
    """Reads noun phrases against the vocabulary of one perspective's index."""

    def __init__(self, index: PerspectiveIndex, speaker: str, addressee: str, it: str | None):
        self.index = index
        self.speaker, self.addressee, self.it = speaker, addressee, it
        self.nouns: dict[tuple[str, ...], str] = {}
        for kind in index.having.get("type", {}):
            words = index.labels.get(kind, humanize(kind)).split()
            self.nouns[tuple(words)] = kind
        self.adjectives = {**_WORDS, **{humanize(v): (a, v) for a, values in index.having.items()
                                        if a != "type" for v in values}}
        self.prepositions = {tuple(text.split()): p for p, text in RELATIONS.items()}
        self.agents = {humanize(t): t for t in index.entities
                       if index.values.get(t, {}).get("type", set()) & AGENT_TYPES}
        self.vocabulary = ({w for n in self.nouns for w in n} | set(self.adjectives)
                           | {w for p in self.prepositions for w in p} | set(self.agents)
                           | {"thing", "object", "one"} | set(_ORDINALS))

    def read(self, words: Sequence[str], agentive: bool) -> Query | None:
        """A query for ``words`` as one noun phrase (an agent's name, if ``agentive``)."""
        text = " ".join(words)
        if agentive:
            if text in ("me", "myself"):
                return Query(name=self.speaker, words=text)
            if text in ("you", "yourself"):
                return Query(name=self.addressee, words=text)
            found = self.agents.get(text)
            return Query(name=found, words=text) if found else None
        if text == "it":
            return Query(name=self.it, words=text) if self.it else None
        return self._phrase(list(words), text, relations=True)

    def _phrase(self, words: list[str], text: str, relations: bool) -> Query | None:
        if words and words[0] in _DETERMINERS:
            words = words[1:]
        adjectives: list[tuple[str, str]] = []
        while words and words[0] in self.adjectives:
            adjectives.append(self.adjectives[words[0]])
            words = words[1:]
        kind: str | None = None
        for size in (3, 2, 1):
            head = tuple(words[:size])
            if len(head) == size and (head in self.nouns or head in {("one",), ("thing",),
                                                                     ("object",)}):
                kind = self.nouns.get(head)
                words = words[size:]
                break
        else:
            return None
        found: list[tuple[str, Query]] = []
        while words:
            if not relations:
                return None
            step = self._relation(words)
            if step is None:
                return None
            predicate, landmark, words = step
            found.append((predicate, landmark))
        return Query(kind, tuple(adjectives), tuple(found), words=text)

    def _relation(self, words: list[str]) -> tuple[str, Query, list[str]] | None:
        for preposition, predicate in self.prepositions.items():
            if tuple(words[:len(preposition)]) != preposition:
                continue
            rest = words[len(preposition):]
            # The landmark is the longest noun phrase without relations of its own;
            # later relations attach to the head ("the cube on the table near the box").
            for end in range(len(rest), 0, -1):
                text = " ".join(rest[:end])
                landmark = self.agents.get(text)
                query = Query(name=landmark, words=text) if landmark else \
                    self._phrase(rest[:end], text, relations=False)
                if query is not None:
                    return predicate, query, rest[end:]
        return None


# -- resolving -----------------------------------------------------------------------------------

def resolve(request: Request, index: PerspectiveIndex,
            referrer: Referrer | None = None) -> Resolution:
    """The things each parameter of ``request`` denotes in ``index``, and what to say.

    ``referrer`` describes the candidates of a disambiguation question (in
    the listener's perspective; by default over ``index``).
    """
    reg = referrer or Referrer(index)
    matches = {role: query.matches(index) for role, query in request.params.items()}
    for role in request.roles:
        if not matches[role]:
            query = request.params[role]
            return Resolution("none", matches, message=f"I see no {_bare(query)}.", role=role)
    for role in request.roles:
        candidates = matches[role]
        if len(candidates) > 1:
            query = request.params[role]
            said = [(a, v) for a, v in query.attributes]
            descriptions = tuple(reg.describe(c, context=candidates, given=said)
                                 for c in candidates)
            first = descriptions[0]
            texts = [first.text()] + [_second(d, first) for d in descriptions[1:]]
            choice = ", ".join(texts[:-1]) + " or " + texts[-1]
            return Resolution("several", matches, question=f"Do you mean {choice}?", role=role,
                              candidates=tuple(candidates), descriptions=descriptions,
                              gestures=tuple(d.gesture for d in descriptions if d.gesture))
    return Resolution("one", matches, bindings={r: m[0] for r, m in matches.items()})


def _bare(query: Query) -> str:
    """The noun phrase as said, without its determiner: "green cube on the shelf"."""
    words = query.words.split()
    return " ".join(words[1:] if words and words[0] in _DETERMINERS else words) or "such thing"


def _second(description: Description, first: Description) -> str:
    """A later candidate of a question: "the one on the shelf" (or "the big one …") when it
    has the first's noun, its full description otherwise."""
    if description.pointing or description.name is not None:
        return description.text()
    if description.noun == first.noun:
        return description.text("one")
    return description.text()


def interpret_answer(answer: str, resolution: Resolution, index: PerspectiveIndex) -> str | None:
    """The candidate the person chose in answering the question of ``resolution``
    ("the one on the table", "the red one", "the first"), or None when the answer
    fits none or several of them."""
    words = [w for w in _words(answer) if w not in ("i", "mean", "yes", "please", "no")]
    candidates = list(resolution.candidates)
    if not words or not candidates:
        return None
    for word in words:
        if word in _ORDINALS and words[-1] in (word, "one"):
            position = _ORDINALS[word]
            return candidates[position] if -len(candidates) <= position < len(candidates) else None
    nps = _NounPhrases(index, "", "", None)
    query = nps.read(words, agentive=False)
    if query is None:
        query = nps.read(words + ["one"], agentive=False)  # "the red" / "on the table"
    if query is None:
        query = nps.read(["one"] + words, agentive=False)
    if query is None:
        return None
    found = query.matches(index, among=candidates)
    return found[0] if len(found) == 1 else None

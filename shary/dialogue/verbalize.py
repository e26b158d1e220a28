"""Verbalization: an action label and its bound parameters said as a sentence.

JAHRVIS (Section VI-A.1 and VI-E) stores a verbal label with every action of
its ontology, in a small grammar: ``{Agent} @Place {Pickable} on {Support}``.
Words in braces are the action's parameters, filled when the robot speaks;
``@`` marks the verb, which is conjugated; every other word is said as it is.
The communicative act decides tense, person and mood:

=================  =======================================================
act                sentence (the robot speaks to Alice)
=================  =======================================================
``inform-done``    I placed the blue cube on the stick. / You placed …
``inform-ongoing`` I am placing the blue cube on the stick.
``inform-planned`` I will place … / You will place …
``inform-failed``  I could not place …
``inform-dropped`` I will not place … (a task given up or refused)
``request``        Please place the blue cube on the stick.
``question``       Can you place the blue cube on the stick?
``ask-done``       Did you place the blue cube on the stick?
``ask-going``      Are you going to place the blue cube on the stick? (a task not finished)
``propose``        Shall I place …? / Would you like to place …?
=================  =======================================================

The first parameter of a label is the agent (the grammatical subject).  An
agent is *I* when it is the speaker, *you* when it is the addressee, and its
name otherwise (*me* and *you* in object position); other parameters are
named by a ``refer`` function, normally the referring expressions of
:mod:`shary.dialogue.reg` in the listener's perspective, so that "the green
cube on the table" is what the listener can pick out.

A phrasal verb is written with an underscore (``@pick_up``) or with its
particle later in the label (``@pick {Object} up``); only its head is
inflected (lemminflect would say "pick uped").  Conjugation comes from
lemminflect, which knows irregular verbs (gave, took, put); "be" is
conjugated by person (I was, you were), since lemminflect gives both forms.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass

__all__ = ["ACTS", "Label", "Verbalizer", "conjugate", "humanize", "plural", "verbalize"]

ACTS = ("inform-done", "inform-ongoing", "inform-planned", "inform-failed", "inform-dropped",
        "request", "question", "ask-done", "ask-going", "propose")
"""The communicative acts a sentence can carry out (see the module's table)."""

_TOKEN = re.compile(r"\{([^{}\s]+)\}|@([A-Za-z][\w-]*)|([^\s{}@]+)")


@dataclass(frozen=True)
class Label:
    """A parsed action label: the agent's parameter, then the verb phrase's parts.

    ``parts`` holds ``("slot", NAME)``, ``("verb", LEMMA)`` and
    ``("word", TEXT)`` in the label's order; a label has exactly one verb.
    """

    text: str
    agent: str
    parts: tuple[tuple[str, str], ...]

    @staticmethod
    @functools.lru_cache(maxsize=512)
    def parse(text: str) -> Label:
        """Read a label; a ValueError says what is wrong with one that is not."""
        parts: list[tuple[str, str]] = []
        position = 0
        for match in _TOKEN.finditer(text):
            gap = text[position:match.start()]
            if gap.strip():
                raise ValueError(f"label {text!r}: cannot read {gap.strip()!r}; write "
                                 "{Param} for a parameter and @verb for the verb")
            position = match.end()
            slot, verb, word = match.groups()
            if slot:
                parts.append(("slot", slot))
            elif verb:
                parts.append(("verb", verb.lower().replace("_", " ")))
            else:
                parts.append(("word", word))
        rest = text[position:]
        if rest.strip():
            raise ValueError(f"label {text!r}: cannot read {rest.strip()!r}; write "
                             "{Param} for a parameter and @verb for the verb")
        if not parts or parts[0][0] != "slot":
            raise ValueError(f"label {text!r} must start with its agent, e.g. "
                             "'{Agent} @Place {Pickable} on {Support}'")
        verbs = [p for p in parts if p[0] == "verb"]
        if len(verbs) != 1:
            raise ValueError(f"label {text!r} must mark exactly one verb with '@' "
                             f"(it marks {len(verbs)})")
        if parts[1][0] != "verb":
            raise ValueError(f"label {text!r}: the verb must follow the agent")
        return Label(text, parts[0][1], tuple(parts[1:]))

    @property
    def params(self) -> tuple[str, ...]:
        """The label's parameters, the agent first."""
        return (self.agent,) + tuple(v for k, v in self.parts if k == "slot")


@functools.lru_cache(maxsize=4096)
def conjugate(verb: str, form: str, person: int = 3) -> str:
    """``verb`` (a lemma, possibly phrasal: "pick up") in a Penn tag's form.

    ``form`` is VB (base), VBD (past), VBG (-ing), VBN (past participle),
    VBZ (third person present) or VBP (other present); ``person`` (1, 2 or 3,
    singular) chooses between "was" and "were" and among "am", "are", "is".
    """
    head, _, particle = verb.partition(" ")
    if head == "be":
        word = {"VB": "be", "VBG": "being", "VBN": "been",
                "VBD": "were" if person == 2 else "was",
                "VBZ": "is", "VBP": {1: "am", 2: "are"}.get(person, "is")}[form]
    elif form == "VB":
        word = head
    else:
        # Imported when first needed: lemminflect costs about 0.2 s to import and
        # 0.6 s to load its tables, which a run that never speaks need not pay.
        from lemminflect import getInflection

        found = getInflection(head, form)
        # lemminflect lists the regular form last for verbs with two ("lay", "lied"):
        # its first is the usual one.
        word = found[0] if found else head
    return f"{word} {particle}" if particle else word


@functools.lru_cache(maxsize=1024)
def plural(noun: str) -> str:
    """A noun phrase's plural, inflecting its last word: "coffee table" -> "coffee tables",
    "box" -> "boxes" (lemminflect, imported when first needed as in :func:`conjugate`)."""
    from lemminflect import getInflection

    head, _, last = noun.rpartition(" ")
    found = getInflection(last, "NNS")
    word = found[0] if found else last + "s"
    return f"{head} {word}" if head else word


def humanize(name: str) -> str:
    """An identifier as words: ``yellow-bottle`` -> "yellow bottle", ``CoffeeTable`` ->
    "coffee table"."""
    text = re.sub(r"(?<=[a-z0-9])(?=[A-Z])", " ", str(name)).replace("-", " ").replace("_", " ")
    return " ".join(text.split()).lower()


def proper(name: str) -> str:
    """A person's name as said: ``alice`` -> "Alice"."""
    return humanize(name).title()


def _default_refer(thing: str) -> str:
    return "the " + humanize(thing)


def _proper(name: str) -> str:
    words = humanize(name)
    return words[:1].upper() + words[1:]


def verbalize(label: str | Label, bindings: Mapping[str, object], act: str, *,
              speaker: str, addressee: str | None = None,
              agents: frozenset[str] | set[str] = frozenset(),
              refer: Callable[[str], str] | None = None) -> str:
    """The sentence that carries out ``act`` about the action ``label`` with ``bindings``.

    ``bindings`` maps each parameter of the label (case does not matter) to
    a name; ``speaker`` and ``addressee`` are agents' names; ``agents`` are
    the other names that are people or robots (said by name, not described);
    ``refer`` says how to name any other thing (``"the " + words`` if not
    given).  A ValueError names an unknown act or a parameter left unbound.
    """
    parsed = label if isinstance(label, Label) else Label.parse(label)
    if act not in ACTS:
        raise ValueError(f"unknown communicative act {act!r}; one of: {', '.join(ACTS)}")
    values = {str(k).lower(): str(v) for k, v in bindings.items() if v is not None}
    missing = [p for p in parsed.params if p.lower() not in values]
    if missing:
        raise ValueError(f"label {parsed.text!r}: no value for {', '.join(missing)}")
    describe = refer or _default_refer
    known = set(agents) | {speaker} | ({addressee} if addressee else set())

    def name(thing: str, subject: bool) -> str:
        if thing == speaker:
            return "I" if subject else "me"
        if thing == addressee:
            return "you"
        if thing in known:
            return _proper(thing)
        return describe(thing)

    agent = values[parsed.agent.lower()]
    person = 1 if agent == speaker else 2 if agent == addressee else 3
    subject = name(agent, True)
    verb = next(v for k, v in parsed.parts if k == "verb")
    rest = [(k, name(values[v.lower()], False) if k == "slot" else v)
            for k, v in parsed.parts if k != "verb"]
    tail = " ".join(_dative_shift(verb, rest))

    def phrase(form: str) -> str:
        return " ".join(w for w in (conjugate(verb, form, person), tail) if w)

    if act == "inform-done":
        sentence = f"{subject} {phrase('VBD')}."
    elif act == "inform-ongoing":
        sentence = f"{subject} {conjugate('be', 'VBP', person)} {phrase('VBG')}."
    elif act == "inform-planned":
        sentence = f"{subject} will {phrase('VB')}."
    elif act == "inform-failed":
        sentence = f"{subject} could not {phrase('VB')}."
    elif act == "inform-dropped":
        sentence = f"{subject} will not {phrase('VB')}."
    elif act == "request":
        sentence = f"Please {phrase('VB')}." if person == 2 else \
            f"Please let {name(agent, False)} {phrase('VB')}."
    elif act == "question":
        sentence = f"Can {subject} {phrase('VB')}?"
    elif act == "ask-done":
        sentence = f"Did {subject} {phrase('VB')}?"
    elif act == "ask-going":
        sentence = f"{conjugate('be', 'VBP', person)} {subject} going to {phrase('VB')}?"
    elif person == 2:  # propose
        sentence = f"Would you like to {phrase('VB')}?"
    else:
        sentence = f"Shall {subject} {phrase('VB')}?"
    return sentence[:1].upper() + sentence[1:]


_DATIVE_VERBS = frozenset({"give", "hand", "bring", "pass", "show", "send", "offer", "lend"})


def _dative_shift(verb: str, rest: list[tuple[str, str]]) -> list[str]:
    """English puts a pronoun recipient first: "give you the bottle", not "give the bottle
    to you" (the label's "@Give {Object} to {Partner}" reads both ways)."""
    if verb in _DATIVE_VERBS and len(rest) == 3 and rest[0][0] == "slot" \
            and rest[1] == ("word", "to") and rest[2][1] in ("me", "you"):
        return [rest[2][1], rest[0][1]]
    return [text for _, text in rest]


class Verbalizer:
    """Sentences from one speaker to one listener, objects named in the listener's terms.

    ``refer`` is usually :meth:`shary.dialogue.reg.Referrer.text` over the
    listener's perspective; ``agents`` are the names of people and robots.
    """

    def __init__(self, speaker: str, addressee: str | None = None, *,
                 agents: frozenset[str] | set[str] = frozenset(),
                 refer: Callable[[str], str] | None = None):
        self.speaker = speaker
        self.addressee = addressee
        self.agents = frozenset(agents)
        self.refer = refer

    def say(self, label: str | Label, bindings: Mapping[str, object], act: str) -> str:
        """The sentence for ``act`` about ``label`` (see :func:`verbalize`)."""
        return verbalize(label, bindings, act, speaker=self.speaker, addressee=self.addressee,
                         agents=self.agents, refer=self.refer)

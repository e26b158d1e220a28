"""Requests that fit several things: 0 -> say so, 1 -> go on, several -> ask which.

A person's request names its things by description (``{type: Cube, color:
green}``: the green cube).  :func:`matches` finds what fits in the robot's
perspective of the fact base.  When several things fit, a ``disambiguate``
task (``schemes/disambiguate.yaml``) asks the partner which one, naming each
by what tells it apart from the others ("Do you mean the green cube on the
coffee table or the one on the shelf?"), and understands the answer: a
description (``{isOn: shelf}``) that exactly one of them fits.

A :class:`Question` holds one such dialogue; the ``disambiguate`` task's
``question`` argument names it, and its recipes' functions
(:func:`ask_which`, :func:`understand_which`) read it.  Understanding the
answer records the choice on the question; whoever asked it reads the choice
when the task ends.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from shary.dialogue import say
from shary.dialogue.reg import ATTRIBUTES, Referrer
from shary.dialogue.verbalize import humanize
from shary.recipes import Recipe, Step

if TYPE_CHECKING:
    from shary.supervisor import TaskRun

_PLACE_WORDS = {"isOn": "on", "isIn": "in"}


def matches(facts: Any, description: dict[str, Any], perspective: str = "robot") -> list[str]:
    """The things (sorted) of which every (predicate, value) of ``description`` holds."""
    pairs = [(str(p), str(v)) for p, v in description.items()]
    if not pairs:
        return []
    first_p, first_v = pairs[0]
    found = {str(s) for s, p, o in facts.triples(perspective)
             if str(p) == first_p and str(o) == first_v}
    return sorted(thing for thing in found
                  if all(facts.holds(thing, p, v, perspective) for p, v in pairs[1:]))


def contrast(facts: Any, things: list[str], description: dict[str, Any] | None = None,
             perspective: str = "robot") -> list[str]:
    """Each thing named by what tells it from the others, in the listener's words
    (referring expressions, :mod:`shary.dialogue.reg`): ``the green cube on the coffee
    table``, then ``the one on the store table``; what the person said is kept."""
    referrer = Referrer.for_perspective(facts, perspective)
    given = [(str(p), str(v)) for p, v in (description or {}).items() if p in ATTRIBUTES]
    named = []
    for i, thing in enumerate(things):
        found = referrer.describe(thing, context=things, given=given)
        named.append(found.text(head="one" if i and found.relations and not found.pointing
                                else None))
    return named


def question_text(facts: Any, things: list[str], description: dict[str, Any] | None = None,
                  perspective: str = "robot") -> str:
    """``Do you mean A, B or C?``"""
    named = contrast(facts, things, description, perspective)
    return f"Do you mean {', '.join(named[:-1])} or {named[-1]}?"


def described(description: dict[str, Any]) -> str:
    """A description in words, as the person gave it: ``blue cube`` (for "no such")."""
    colour = description.get("color")
    kind = description.get("type")
    where = [f"{_PLACE_WORDS[p]} the {humanize(str(v))}" for p, v in description.items()
             if p in _PLACE_WORDS]
    words = [humanize(str(colour))] if colour else []
    words.append(humanize(str(kind)).lower() if kind else "such thing")
    return " ".join(words + where)


@dataclass(eq=False)
class Question:
    """One "which one do you mean?" dialogue: who asked for what, what fits, the choice."""

    id: str
    partner: str
    param: str
    candidates: list[str]
    description: dict[str, Any]
    """What the person said of the thing (kept in the question's words)."""
    then: Callable[[Question], Any]
    """Called when the dialogue is over (with :attr:`chosen` set or not)."""
    chosen: str | None = None
    answers: list[Any] = field(default_factory=list)


def _question(run: TaskRun) -> Question:
    return run.sup.dialogue.questions[str(run.env["question"])]


def ask_which(run: TaskRun, recipe: Recipe) -> list[Step]:
    """The ASK-WHICH recipe: ask the question (the partner attends: the scheme waited)."""
    q = _question(run)
    return [say("ask", question_text(run.sup.facts, q.candidates, q.description))]


def understand_which(run: TaskRun, recipe: Recipe) -> list[Step]:
    """The SAY-WHICH recipe: keep the things the answer fits; exactly one is the choice
    (``chosen``), otherwise the robot says it did not understand (``unclear``)."""
    q = _question(run)
    heard = run.entered_data.get("SAY-WHICH") or {}
    answer = (heard.get("data") or {}) if isinstance(heard, dict) else {}
    q.answers.append(answer)
    choice = answer.get("choice") if isinstance(answer, dict) else None
    left = ([t for t in q.candidates if all(run.sup.facts.holds(t, p, v)
                                            for p, v in choice.items())]
            if isinstance(choice, dict) and choice else [])
    if len(left) == 1:
        q.chosen = left[0]
        others = [t for t in q.candidates if t != left[0]]
        named = contrast(run.sup.facts, [left[0], *others], q.description)[0]
        return [say("understood", f"All right, {named}.", emit="chosen")]
    return [say("unclear", "Sorry, I did not understand which one.", emit="unclear")]

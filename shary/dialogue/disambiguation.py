"""Requests that fit several things: 0 -> say so, 1 -> go on, several -> ask which.

What a person asks for names its things by description: a sentence read by
:mod:`shary.dialogue.requests` ("give me the green cube"), or an act whose
arguments are descriptions (``{type: Cube, color: green}``, read by
:func:`query_of`).  Either way each parameter is a
:class:`~shary.dialogue.requests.Query`, and
:func:`~shary.dialogue.requests.resolve` says what fits in the robot's
perspective: nothing (the robot says so), one thing, or several, with the
question that names each by a referring expression ("Do you mean the green
cube on the coffee table or the one on the store table?").

Several: a ``disambiguate`` task (``schemes/disambiguate.yaml``) asks the
question once the partner attends, and understands the answer: a sentence
("the one on the store table", read by
:func:`~shary.dialogue.requests.interpret_answer`) or a description
(``{isOn: store-table}``) that exactly one candidate fits.  A
:class:`Question` holds one such dialogue; the task's ``question`` argument
names it, and its recipes' functions (:func:`ask_which`,
:func:`understand_which`) read it.  Understanding the answer records the
choice on the question; whoever asked reads it when the task ends.  What the robot
says is said to a partner who attends: the question waits for them again when they
looked away, the acknowledgement ("All right, the one on the store table.") is left
unsaid (the robot turns to them).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from shary.dialogue import attention
from shary.dialogue.reg import RELATIONS, PerspectiveIndex
from shary.dialogue.requests import Query, Resolution, interpret_answer
from shary.dialogue.steps import say
from shary.kernel.recipes import Recipe, Step

if TYPE_CHECKING:
    from shary.kernel.supervisor import TaskRun


def query_of(value: Any) -> Query:
    """A parameter's value as a query: a thing's name, or a description
    (``{type: Cube, color: green, isOn: store-table}``: relations name their landmark)."""
    if not isinstance(value, dict):
        return Query(name=str(value), words=str(value))
    attributes = tuple((str(p), str(v)) for p, v in value.items()
                       if p != "type" and p not in RELATIONS)
    relations = tuple((str(p), Query(name=str(v), words=str(v))) for p, v in value.items()
                      if p in RELATIONS)
    kind = value.get("type")
    words = " ".join([v for p, v in attributes] + ([str(kind).lower()] if kind else ["thing"]))
    return Query(str(kind) if kind else None, attributes, relations, words="the " + words)


@dataclass(eq=False)
class Question:
    """One "which one do you mean?" dialogue: who asked, what fits, the choice."""

    id: str
    partner: str
    resolution: Resolution
    then: Callable[[Question], Any]
    """Called when the dialogue is over (with :attr:`chosen` set or not)."""
    chosen: str | None = None
    answers: list[Any] = field(default_factory=list)


def _question(run: TaskRun) -> Question:
    return run.sup.dialogue.questions[str(run.env["question"])]


def ask_which(run: TaskRun, recipe: Recipe) -> list[Step]:
    """The ASK-WHICH recipe: ask the question once the partner attends (the scheme waited;
    one who looked away since is waited for again)."""
    return attention.await_attention(run, "ask") or [
        say("ask", str(_question(run).resolution.question))]


def chosen_by(answer: Any, q: Question, facts: Any) -> str | None:
    """The candidate an answer picks out: ``{text: SENTENCE}`` or ``{choice:
    DESCRIPTION}`` (a person's act); None when it fits none or several."""
    if not isinstance(answer, dict):
        return None
    candidates = list(q.resolution.candidates)
    if isinstance(answer.get("text"), str):
        index = PerspectiveIndex.from_facts(facts, "robot")
        return interpret_answer(answer["text"], q.resolution, index)
    choice = answer.get("choice")
    if isinstance(choice, dict) and choice:
        left = [t for t in candidates if all(facts.holds(t, p, v) for p, v in choice.items())]
        return left[0] if len(left) == 1 else None
    return None


def understand_which(run: TaskRun, recipe: Recipe) -> list[Step]:
    """The SAY-WHICH recipe: the thing the answer picks out is the choice (``chosen``,
    the thing its event's data: the scheme keeps it); otherwise the robot says it did not
    understand (``unclear``)."""
    q = _question(run)
    heard = run.entered_data.get("SAY-WHICH") or {}
    answer = heard.get("data") if isinstance(heard, dict) else None
    q.answers.append(answer)
    found = chosen_by(answer, q, run.sup.facts)
    if found is None:
        return [attention.if_attending(
            run, say("unclear", "Sorry, I did not understand which one.", emit="unclear"))]
    q.chosen = found
    described = q.resolution.descriptions[list(q.resolution.candidates).index(found)]
    return [attention.if_attending(run, say("understood", f"All right, {described.text()}.",
                                            emit="chosen", emit_data={"thing": found}))]

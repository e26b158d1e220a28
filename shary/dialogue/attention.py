"""Attention before speaking: nothing is said to a person who does not attend.

A communication waits until the robot perceives its partner attending to it
(in the robot's perspective, ``PARTNER looksAt ROBOT``: perception only
states it of a person it sees, whose gaze it sees on itself, so the person
is there and can hear it).  How long it waits, and what comes after (another
modality: calling the person by name; or giving up without speaking), is
the ``inform`` scheme's (``schemes/inform.yaml``); its WAIT-ATTENTION
recipes (``recipes/dialogue.yaml``) end at once when the partner attends
already, and otherwise when the fact appears.

:func:`tell` is how any part of the robot says something unprompted (the
dialogue's "I found no such thing", JAHRVIS's informs of what a person did not
see): it starts an ``inform`` task.  :func:`announce` is how it says why it
stops (a failed shared plan): that is said whoever listens, since the verdict
is reached and waiting for a glance could last for ever (an ``announce``
task).  Neither speaks to a person who has left (:func:`departed`): an
inform ends at once untold, an announcement is logged as an ``unheard`` row.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from shary.dialogue.steps import look, say
from shary.dialogue.verbalize import proper
from shary.kernel.recipes import INITIATOR_PARAM, Recipe, Step

if TYPE_CHECKING:
    from shary.kernel.supervisor import Supervisor, TaskRun

INFORM_TASK = "inform"
ANNOUNCE_TASK = "announce"
ATTENTION_LOST = "attention-lost"
"""The event that sends a scheme back to waiting for its partner's attention."""
LEFT = "left"
"""The event that tells a task its person has left (``schemes/inform.yaml``)."""
ATTENDS = "looksAt"


def attending(facts: Any, person: str, robot: str, perspective: str = "robot") -> bool:
    """Whether the robot perceives ``person`` attending to it now."""
    return facts.holds(person, ATTENDS, robot, perspective)


def listening(run: TaskRun) -> bool:
    """Whether the task's partner attends to the robot (or the task has none): what the
    robot says to them is said only then."""
    partner = run.roles.get("partner")
    return partner is None or attending(run.sup.facts, str(partner), run.robot)


def if_attending(run: TaskRun, sentence: Step) -> Step:
    """``sentence`` when the partner attends; else a turn of the head to them, silent,
    that emits what the sentence would have: nothing is said to a person who does not
    attend, and the scheme goes on as if it had been (an acknowledgement is no news to
    them), as the END-TASK recipes do."""
    if listening(run):
        return sentence
    return look(sentence.name, str(run.roles["partner"]), sentence.after, sentence.emit,
                sentence.emit_data)


def await_attention(run: TaskRun, name: str) -> list[Step]:
    """Instead of a question or a proposal to a partner who does not attend: the robot
    turns to them without a word, and its scheme waits for their attention
    (``attention-lost``) before asking; nothing (go on and ask) when they attend."""
    if listening(run):
        return []
    return [look(name, str(run.roles["partner"]), emit=ATTENTION_LOST)]


def call_attention(run: TaskRun, recipe: Recipe) -> list[Step]:
    """CALL-ATTENTION: another modality than waiting for a glance: look at the person
    and call them by name ("Excuse me, Alice."); the person is the task's partner, its
    helper (ask-help), or the person who asked for it."""
    partner = str(run.env.get("partner") or run.env.get("helper") or run.env[INITIATOR_PARAM])
    return [look("look", partner), say("call", f"Excuse me, {proper(partner)}.",
                                       after=("look",))]


def departed(sup: Supervisor, person: str) -> bool:
    """Whether ``person`` has left the robot (their session closed, or they are perceived
    no more), when the robot keeps sessions (:mod:`shary.dialogue.sessions`)."""
    sessions = sup.dialogue.sessions
    return sessions is not None and sessions.gone(person)


def tell(sup: Supervisor, partner: str, text: str,
         on_finish: Callable[[TaskRun], Any] | None = None) -> TaskRun:
    """Say ``text`` to ``partner`` once they attend (an ``inform`` task; its outcome is
    ``done`` when it was said, ``failed`` when the partner never attended, at once when
    they have left: nobody is called in an empty room)."""
    run = sup.start_task(INFORM_TASK, {"partner": partner, "text": text}, on_finish=on_finish)
    if departed(sup, partner):
        run.deliver(LEFT)
    return run


def announce(sup: Supervisor, partner: str, text: str) -> TaskRun | None:
    """Say ``text`` to ``partner`` whoever listens (an ``announce`` task), or, when they
    have left, log it as ``unheard`` and say nothing."""
    if departed(sup, partner):
        sup.record("unheard", agent=partner, text=text, why=f"{partner} has left")
        return None
    return sup.start_task(ANNOUNCE_TASK, {"partner": partner, "text": text})

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
see): it starts an ``inform`` task.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from shary.dialogue.steps import look, say
from shary.dialogue.verbalize import proper
from shary.kernel.recipes import Recipe, Step

if TYPE_CHECKING:
    from shary.kernel.supervisor import Supervisor, TaskRun

INFORM_TASK = "inform"
ATTENDS = "looksAt"


def attending(facts: Any, person: str, robot: str, perspective: str = "robot") -> bool:
    """Whether the robot perceives ``person`` attending to it now."""
    return facts.holds(person, ATTENDS, robot, perspective)


def call_attention(run: TaskRun, recipe: Recipe) -> list[Step]:
    """CALL-ATTENTION: another modality than waiting for a glance: look at the partner
    and call them by name ("Excuse me, Alice.")."""
    partner = str(run.env["partner"])
    return [look("look", partner), say("call", f"Excuse me, {proper(partner)}.",
                                       after=("look",))]


def tell(sup: Supervisor, partner: str, text: str,
         on_finish: Callable[[TaskRun], Any] | None = None) -> TaskRun:
    """Say ``text`` to ``partner`` once they attend (an ``inform`` task; its outcome is
    ``done`` when it was said, ``failed`` when the partner never attended)."""
    return sup.start_task(INFORM_TASK, {"partner": partner, "text": text}, on_finish=on_finish)

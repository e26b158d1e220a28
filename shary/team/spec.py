"""What a team file says, as plain data: agents, behaviours, scoring, the goal's tasks.

A team file (docs/teams.md) is read by :mod:`shary.team.teamfile` into a
:class:`TeamSpec`; :class:`shary.team.team.Team` builds the running team
from it.  Nothing here runs: these are the declarations, checked for meaning
when read (every task's skill is someone's, constraints have no cycle …).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROBOT, HUMAN, SOFTWARE = "robot", "human", "software"
ACCEPT, REFUSE, IGNORE, ANSWER = "accept", "refuse", "ignore", "answer"

Delay = tuple[float, float]
"""Seconds, drawn uniformly in [low, high] from the run's seeded generator."""

WATCHDOG = 300.0
"""Seconds without progress in the goal before the Task Manager's watchdog acts, unless
the team file's ``goal: watchdog:`` says otherwise (HRI/OS gives no figure: five
minutes outlasts any one step of the seam-welding goal)."""


@dataclass(frozen=True)
class Reply:
    """How a simulated person replies to an assignment or a question, and when."""

    reply: str
    after: Delay = (1.0, 1.0)


@dataclass(frozen=True)
class HelpRequest:
    """Help a simulated person asks for on their own: at a time, a skill, arguments."""

    at: float
    ask: str
    args: dict[str, Any] = field(default_factory=dict)
    release: float = 10.0
    """Seconds after being served before the person releases the helper."""


@dataclass(frozen=True)
class Behaviour:
    """The simulated person behind a human proxy (HRI/OS's user, played by a profile)."""

    assignments: Reply = Reply(ACCEPT, (1.0, 2.0))
    questions: Reply = Reply(ANSWER, (2.0, 5.0))
    works: dict[str, Delay] = field(default_factory=dict)
    """Skill -> how long the person takes over a task of it (``*``: any other skill)."""
    answers: dict[str, str] = field(default_factory=dict)
    """Question topic -> the answer given (otherwise yes, or the first choice)."""
    requests: tuple[HelpRequest, ...] = ()

    def work_time(self, skill: str) -> Delay:
        return self.works.get(skill) or self.works.get("*") or (30.0, 30.0)


@dataclass(frozen=True)
class AgentSpec:
    """One team member as declared: kind, skills, resources, services, place."""

    name: str
    kind: str
    skills: tuple[str, ...] = ()
    resources: tuple[str, ...] = ()
    services: tuple[str, ...] = ()
    at: tuple[float, ...] | None = None
    remote: bool = False
    behaviour: Behaviour | None = None
    """For a human: the simulated person (None: a real person answers through the proxy)."""
    doc: str = ""


@dataclass(frozen=True)
class TaskSpec:
    """One high-level task of the goal (Fig. 2): a skill, arguments, constraints."""

    name: str
    skill: str
    args: dict[str, Any] = field(default_factory=dict)
    after: tuple[str, ...] = ()
    by: tuple[str, ...] = ()
    needs: tuple[str, ...] = ()
    """Resources the agent must have besides the skill."""
    at: tuple[float, ...] | None = None
    attempts: int = 2
    respawn: str | None = None
    reply_within: float = 30.0
    doc: str = ""


@dataclass(frozen=True)
class QuestionSpec:
    """A question robots may ask (the atomic task ``ask`` names its topic)."""

    topic: str
    text: str
    type: str = "yes-no"
    choices: tuple[str, ...] = ()
    priority: int = 0
    expires: float = 60.0
    wait: bool = True
    """The asking robot waits for the answer; otherwise it keeps working."""
    accept: tuple[str, ...] = ()
    """Answers that let the asking step succeed (empty: any answer)."""
    fallback: str | None = None
    """The answer taken when nobody answered in time (None: the step fails)."""


@dataclass(frozen=True)
class TeamSpec:
    """A whole team file."""

    name: str
    agents: dict[str, AgentSpec]
    tasks: dict[str, TaskSpec]
    weights: dict[str, float]
    """Criterion -> weight (normalised to sum 1)."""
    questions: dict[str, QuestionSpec] = field(default_factory=dict)
    recipes: tuple[Path, ...] = ()
    doc: str = ""
    file: str = ""
    watchdog: float = WATCHDOG
    """Seconds without progress in the goal after which the Task Manager's watchdog acts
    (``goal: watchdog:``; :mod:`shary.team.tasks`)."""

    def of_kind(self, kind: str) -> list[AgentSpec]:
        return [a for a in self.agents.values() if a.kind == kind]

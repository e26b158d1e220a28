"""The Resource Manager: which agent for a task, a question or a help request, and why.

HRI/OS (Section 3.3): "the RM performs delegation using multiple criteria
that vary with time and situation, rather than simple capability match
making ... each criterion is reasoned about by a meta-agent".  Here each
criterion is a :class:`Scorer` (a meta-agent): it scores one agent for one
:class:`Need` between 0 and 1, or says the agent cannot serve it at all
(``None``).  :meth:`ResourceManager.rank` combines the scores with the team
file's weights (given directly, or as AHP pairwise comparisons computed by
``planner/evaluation/ahp.py``) and logs its choice with every criterion's part, so a
delegation can always be explained from the context log.

Adding a criterion is adding a scorer (:meth:`ResourceManager.add`), not
changing the others.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from shary.team.agents import Agent

TASK, QUESTION, HELP = "task", "question", "help"

CRITERIA = ("capability", "availability", "distance", "workload", "activity", "past-answers")
"""The built-in criteria (a team file's ``scoring`` names them)."""
DEFAULT_WEIGHTS = {"capability": 3.0, "availability": 3.0, "distance": 1.0, "workload": 1.0,
                   "activity": 2.0, "past-answers": 2.0}
WORKLOAD_WINDOW = 600.0
"""Seconds of past assignments the workload criterion counts."""


@dataclass(frozen=True)
class Need:
    """What is asked of an agent: a task's skill, a question, or help with a skill."""

    what: str
    skill: str | None = None
    at: tuple[float, ...] | None = None
    kinds: tuple[str, ...] = ("robot", "human")
    by: tuple[str, ...] = ()
    """Only these agents (empty: any)."""
    needs: tuple[str, ...] = ()
    """Resources the agent must have (a camera, a welding tool)."""
    subject: str = ""
    """What the need is for (a task's or a question's id), for the log."""
    requester: str = ""
    """Who asks (a help request: a robot associated with them may serve it)."""


class Scorer(Protocol):
    """A meta-agent: one criterion, scored in [0, 1]; None when the agent cannot serve."""

    name: str

    def score(self, agent: Agent, need: Need, now: float) -> float | None: ...


@dataclass(frozen=True)
class Ranked:
    """One candidate: its combined score and each criterion's part."""

    agent: Agent
    score: float
    parts: dict[str, float]

    def explain(self) -> dict[str, Any]:
        return {"agent": self.agent.name, "score": round(self.score, 4),
                "by": {k: round(v, 3) for k, v in self.parts.items()}}


class Capability:
    """Tasks and help need the skill and the resources named; any human can be asked a
    question."""

    name = "capability"

    def score(self, agent: Agent, need: Need, now: float) -> float | None:
        if need.what == QUESTION:
            return 1.0
        if need.skill not in agent.skills or not agent.resources.issuperset(need.needs):
            return None
        return 1.0


class Availability:
    """Free agents first; a robot associated with someone or under user control cannot
    take more."""

    name = "availability"

    def score(self, agent: Agent, need: Need, now: float) -> float | None:
        return agent.availability(need)


class Distance:
    """Closer is better: 1 / (1 + metres); 0.5 when a position is unknown or the agent
    works remotely (a question does not travel)."""

    name = "distance"

    def score(self, agent: Agent, need: Need, now: float) -> float | None:
        if need.what == QUESTION or need.at is None or agent.position is None:
            return 0.5
        return 1.0 / (1.0 + math.dist(agent.position[:2], need.at[:2]))


class Workload:
    """Fewer assignments over the last :data:`WORKLOAD_WINDOW` seconds is better."""

    name = "workload"

    def score(self, agent: Agent, need: Need, now: float) -> float | None:
        return 1.0 / (1.0 + agent.recent_load(now, WORKLOAD_WINDOW))


class Activity:
    """The human's current activity: idle, answering, working (robots: idle or not)."""

    name = "activity"

    def score(self, agent: Agent, need: Need, now: float) -> float | None:
        return agent.activity_score(need)


class PastAnswers:
    """How the agent answered before: questions answered in time, assignments accepted
    (Laplace's rule: (yes + 1) / (asked + 2), so a newcomer scores 0.5)."""

    name = "past-answers"

    def score(self, agent: Agent, need: Need, now: float) -> float | None:
        yes, asked = agent.track_record(need.what)
        return (yes + 1.0) / (asked + 2.0)


BUILTIN_SCORERS: tuple[type, ...] = (Capability, Availability, Distance, Workload, Activity,
                                     PastAnswers)


class ResourceManager:
    """Ranks agents for a need with weighted scorers (see the module's docstring)."""

    def __init__(self, weights: dict[str, float], now: Callable[[], float],
                 record: Callable[..., None] | None = None):
        self.now = now
        self._record = record
        self.scorers: list[tuple[Scorer, float]] = []
        for cls in BUILTIN_SCORERS:
            scorer = cls()
            if weights.get(scorer.name, 0.0) > 0 or scorer.name == "capability":
                self.scorers.append((scorer, weights.get(scorer.name, 0.0)))

    def add(self, scorer: Scorer, weight: float) -> None:
        """A new criterion (a meta-agent), weighed with the others."""
        self.scorers.append((scorer, weight))

    def rank(self, need: Need, agents: Iterable[Agent]) -> list[Ranked]:
        """Agents that can serve ``need``, best first (ties: the order given)."""
        now = self.now()
        total = sum(w for _, w in self.scorers) or 1.0
        ranked: list[Ranked] = []
        for agent in agents:
            if agent.kind not in need.kinds or (need.by and agent.name not in need.by):
                continue
            parts: dict[str, float] = {}
            score = 0.0
            for scorer, weight in self.scorers:
                value = scorer.score(agent, need, now)
                if value is None:
                    break
                parts[scorer.name] = value
                score += weight * value
            else:
                ranked.append(Ranked(agent, score / total, parts))
        ranked.sort(key=lambda r: -r.score)
        return ranked

    def choose(self, need: Need, agents: Iterable[Agent], *,
               free: Callable[[Agent], bool] = lambda a: True) -> Agent | None:
        """The best agent that ``free`` allows, logged with the runners-up (``delegation``)."""
        ranked = [r for r in self.rank(need, agents) if free(r.agent)]
        chosen = ranked[0].agent if ranked else None
        if self._record is not None:
            self._record("delegation", task=need.subject or None,
                         agent=chosen.name if chosen else None, need=need.what,
                         skill=need.skill, ranking=[r.explain() for r in ranked[:3]],
                         candidates=len(ranked))
        return chosen

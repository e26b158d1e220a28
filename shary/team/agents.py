"""Team agents as peers: what every member has, and software agents.

HRI/OS (Section 3): "each team agent (human, robot, or software) has a set of
skills and resources that they contribute to the team".  Every agent
receives messages from the :class:`~shary.transport.messages.MessagePort` and
answers with messages; the managers never reach into an agent's insides
beyond what the Resource Manager's criteria read (:meth:`Agent.availability`,
:meth:`Agent.activity_score`, :meth:`Agent.track_record`, the position).

The kinds of members: :class:`~shary.team.robot.RobotAgent` (a shary
supervisor each: breakpoints, association, control authority),
:class:`~shary.team.proxy.HumanProxy` (a person, real or simulated), and
:class:`SoftwareAgent` here: an agent that does not change the world and
offers services (the context manager; the spatial reasoner) — an ``Act``
``QUERY`` gets an ``INFORM`` back.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from shary.team.resources import HELP, QUESTION, TASK, Need
from shary.team.spec import AgentSpec
from shary.transport.messages import Act, Message, Progress

if TYPE_CHECKING:
    from shary.team.team import Team

IDLE, WORKING, ANSWERING, ASSOCIATED, CONTROLLED = (
    "idle", "working", "answering", "associated", "controlled")
SYSTEM, USER = "system", "user"
"""Control authority: the robot decides (system) or a human drives it (user)."""
TEAM_PRIORITY = 0
"""The agenda priority of a team task."""
ASSOCIATED_PRIORITY = 100
"""Help requests served during an association run at this priority (above team tasks)."""
CONTROL_PRIORITY = 1000
"""A human in control holds the robot's agenda above everything it would do itself."""

# Acts between agents (the Interaction Manager and the people use them).
REQUEST_HELP, RELEASE, TAKE_CONTROL, HAND_BACK, QUERY, INFORM = (
    "REQUEST-HELP", "RELEASE", "TAKE-CONTROL", "HAND-BACK", "QUERY", "INFORM")


class Agent:
    """What every team member has: name, kind, skills, place, and its track record."""

    def __init__(self, team: Team, spec: AgentSpec):
        self.team = team
        self.spec = spec
        self.name = spec.name
        self.kind = spec.kind
        self.skills = frozenset(spec.skills)
        self.resources = frozenset(spec.resources)
        self.position: tuple[float, ...] | None = spec.at
        self.current: str | None = None
        """The team task this agent holds (offered or running): one at a time."""
        self.activity = IDLE
        self._recent: deque[float] = deque()
        self._record: dict[str, list[int]] = {TASK: [0, 0], QUESTION: [0, 0], HELP: [0, 0]}
        team.port.subscribe(self.name, self.handle)

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name} {self.activity}>"

    # -- what the Resource Manager's criteria read --------------------------------

    def availability(self, need: Need) -> float | None:
        if need.what == QUESTION:
            return 1.0 if self.activity == IDLE else 0.5
        return 1.0 if self.current is None and self.activity == IDLE else 0.2

    def activity_score(self, need: Need) -> float:
        return {IDLE: 1.0, ANSWERING: 0.6, WORKING: 0.3}.get(self.activity, 0.0)

    def track_record(self, what: str) -> tuple[int, int]:
        """(positive replies, requests) of one kind: accepted tasks, answered questions."""
        yes, asked = self._record[what]
        return yes, asked

    def count(self, what: str, positive: bool) -> None:
        entry = self._record[what]
        entry[1] += 1
        entry[0] += int(positive)

    def recent_load(self, now: float, window: float) -> int:
        recent = self._recent
        while recent and recent[0] < now - window:
            recent.popleft()
        return len(recent)

    def took(self, now: float) -> None:
        self._recent.append(now)

    # -- messages -----------------------------------------------------------------

    def send(self, message: Message) -> None:
        self.team.port.send(message)

    def progress(self, to: str, task: str, status: str, reason: str = "", **data: Any) -> None:
        self.send(Progress(self.name, to, task=task, status=status, reason=reason, data=data))

    def handle(self, message: Message) -> None:
        self.team.record("message-ignored", agent=self.name, type=message.kind)


Service = Callable[[dict[str, Any]], dict[str, Any]]
"""A service: the query's data -> the answer's data."""


class SoftwareAgent(Agent):
    """An agent that does not change the world: it answers ``QUERY`` acts for its services."""

    def __init__(self, team: Team, spec: AgentSpec):
        super().__init__(team, spec)
        self.services: dict[str, Service] = {}

    def offer(self, name: str, service: Service) -> None:
        self.services[name] = service

    def handle(self, message: Message) -> None:
        if not (isinstance(message, Act) and message.act == QUERY):
            super().handle(message)
            return
        name = str(message.data.get("service", ""))
        service = self.services.get(name)
        if service is None:
            result: dict[str, Any] = {"error": f"{self.name} offers no service {name!r} "
                                      f"(it offers {', '.join(sorted(self.services)) or 'none'})"}
        else:
            result = service(dict(message.data))
        self.send(Act(self.name, message.sender, id=message.id, act=INFORM,
                      data={"service": name, **result}, task=message.task))

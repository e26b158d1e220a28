"""The world as an agent of the team: robots and people reach it through the message port.

The world (a PyBullet site, a real robot's drivers) performs the robots' atomic
tasks and the work the people do on site, and takes the pictures questions
carry.  It is an agent like the others, at the address :data:`WORLD`, in this
process or another: nothing here knows which.  :func:`connect_world` gives
each of the team's agents a :class:`WorldLink`:

- a robot's executors: each atomic task becomes an
  :class:`~shary.transport.messages.Assignment` to the world (``id``: the
  request's, ``task``: its node, ``skill``: the atomic task), its outcome a
  :class:`~shary.transport.messages.Progress` back (``done`` with the result in
  ``data``, ``failed`` with the reason); cancelling is a ``CANCEL`` act.  The
  supervisor's :meth:`~shary.kernel.executors.ExecutorRegistry.dispatch` path does
  not change;
- a person's work on site (``mount-panel``): the accepted task, as an
  ``Assignment`` to the world, which moves the person's avatar; its
  ``Progress`` is what the person reports;
- what a question carries: a ``QUERY`` act for the world's ``attach`` service
  (the robot, the topic, the task); the ``INFORM`` it answers is the data.

The world answers at the simulated time it was asked, so a run gives the same
events whether the world is in this process or another.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from shary.kernel.executors import Reporter, Request
from shary.team.agents import INFORM, QUERY
from shary.team.spec import HUMAN, ROBOT
from shary.transport.messages import Act, Assignment, Message, Progress

if TYPE_CHECKING:
    from shary.team.proxy import HumanProxy
    from shary.team.robot import RobotAgent
    from shary.team.team import Team

WORLD = "world"
"""The world agent's address."""
CANCEL = "CANCEL"
"""The act that stops an atomic task the world is performing (``id``: the request's)."""
ATTACH = "attach"
"""The world's service that makes what a question carries (a picture)."""
TEAM_OWN = ("ask",)
"""Atomic tasks the team performs itself (:meth:`shary.team.team.Team.own_executor`)."""


class WorldLink:
    """One agent's link to the world: its requests out, the world's replies back.

    Replies come to the agent's own address; the link takes the ones from the world
    (:meth:`~shary.transport.port.MessagePort.tap`) and leaves the rest to the agent.
    """

    def __init__(self, team: Team, agent: str, world: str = WORLD):
        self.team = team
        self.agent = agent
        self.world = world
        self.waiting: dict[str, Callable[[Message], Any]] = {}
        """Message id -> what to do with the world's reply to it."""
        team.port.tap(agent, self._heard)

    def _heard(self, message: Message) -> bool:
        """Take the world's reply to one of this link's messages (a question the world
        asks the person, for a robot's ``point-light``, is the agent's)."""
        if message.sender != self.world or message.id not in self.waiting:
            return False
        self.waiting.pop(message.id)(message)
        return True

    # -- a robot's executors -----------------------------------------------------------

    def start(self, request: Request, reporter: Reporter) -> None:
        def outcome(message: Message) -> None:
            if not isinstance(message, Progress):
                reporter.failed(request, f"the world answered with {message.kind}")
            elif message.status == "done":
                reporter.done(request, **message.data)
            elif message.status == "cancelled":
                reporter.cancelled(request, message.reason or "cancelled")
            else:
                reporter.failed(request, message.reason or message.status)

        self.waiting[request.id] = outcome
        self.team.port.send(Assignment(self.agent, self.world, id=request.id,
                                       task=request.node, skill=request.atomic,
                                       args=dict(request.args)))

    def cancel(self, request: Request) -> None:
        if self.waiting.pop(request.id, None) is not None:
            self.team.port.send(Act(self.agent, self.world, id=request.id, act=CANCEL,
                                    task=request.node))

    def cut(self) -> None:
        """The agent's process is gone: what it asked the world to do stops (a robot's
        motion is cancelled), and the replies to come are nobody's."""
        for request_id in list(self.waiting):
            self.team.port.send(Act(self.agent, self.world, id=request_id, act=CANCEL))
        self.waiting.clear()

    # -- a person's work on site ------------------------------------------------------

    def performer(self, proxy: HumanProxy) -> Callable[[Assignment], None]:
        """What carries out ``proxy``'s accepted task: the world moves the avatar."""
        def perform(message: Assignment) -> None:
            request_id = self.team.port.new_id("w")

            def over(reply: Message) -> None:
                status = reply.status if isinstance(reply, Progress) else "failed"
                proxy.report(message.task, "done" if status == "done" else "failed",
                             getattr(reply, "reason", ""))

            self.waiting[request_id] = over
            self.team.port.send(Assignment(self.agent, self.world, id=request_id,
                                           task=message.task, skill=message.skill,
                                           args=dict(message.args)))
        return perform

    # -- what questions carry ------------------------------------------------------------

    def attach(self, robot: RobotAgent, request: Request,
               then: Callable[[dict[str, Any]], Any]) -> None:
        """Ask the world what a question of ``request``'s topic carries (see the module's
        docstring); ``then(data)`` with its answer."""
        query_id = self.team.port.new_id("w")

        def informed(reply: Message) -> None:
            data = dict(reply.data) if isinstance(reply, Act) and reply.act == INFORM else {}
            data.pop("service", None)
            then(data)

        self.waiting[query_id] = informed
        self.team.port.send(Act(self.agent, self.world, id=query_id, act=QUERY,
                                task=robot.current, data={
                                    "service": ATTACH, "topic": request.args.get("topic"),
                                    "robot": robot.name, "team-task": robot.current}))


def connect_world(team: Team, world: str = WORLD) -> dict[str, WorldLink]:
    """Make ``world`` perform the team's robots' atomic tasks (all but the team's own) and
    the work of the people on site (not ``remote``), and attach to every question what
    it gives; the links, by agent name."""
    from shary.team.teamfile import robot_library

    links: dict[str, WorldLink] = {}
    robots = team.spec.of_kind(ROBOT)
    if robots:
        atomic = [a for a in robot_library(team.spec).atomic if a not in TEAM_OWN]
        for spec in robots:
            link = links[spec.name] = WorldLink(team, spec.name, world)
            registry = team.robot(spec.name).world
            for name in atomic:
                registry.register(name, link)
    for spec in team.spec.of_kind(HUMAN):
        if not spec.remote:
            link = links[spec.name] = WorldLink(team, spec.name, world)
            proxy = team.human(spec.name)
            for skill in spec.skills:
                proxy.performers[skill] = link.performer(proxy)
    if robots:
        for topic in team.spec.questions:
            team.attach(topic, lambda robot, request, then: links[robot.name].attach(
                robot, request, then))
    return links

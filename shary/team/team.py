"""A running team: agents, managers and the message port on one loop, one log.

:class:`Team` builds what a :class:`~shary.team.spec.TeamSpec` declares:

- one :class:`~shary.kernel.supervisor.Supervisor` per robot (its own schemes,
  agenda and task tree) on the team's :class:`~shary.kernel.loop.EventLoop` and
  context log, with the world's executors (``executors[robot]``: the
  simulation's, a real robot's, or a test's fakes);
- a :class:`~shary.team.agents.HumanProxy` per person, a
  :class:`~shary.team.agents.SoftwareAgent` per software agent;
- the Task, Resource and Interaction Managers, talking to the agents through
  one :class:`~shary.transport.messages.MessagePort`.

Every row the team writes carries the agent's name (a robot's supervisor
writes through :class:`AgentLog`, which names the robot when a row names no
one), and each robot's node and request ids start with its name (``K-10/n3``),
so one log holds the whole team and a timeline has a lane per agent.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from shary.kernel.executors import Executor, ExecutorRegistry, Request
from shary.kernel.loop import EventLoop
from shary.kernel.recipes import RecipeLibrary
from shary.team.agents import HAND_BACK, TAKE_CONTROL, Agent, SoftwareAgent
from shary.team.interaction import AskExecutor, InteractionManager
from shary.team.proxy import HumanProxy
from shary.team.resources import ResourceManager
from shary.team.robot import TELEOPERATE, RobotAgent
from shary.team.spec import HUMAN, ROBOT, TeamSpec
from shary.team.tasks import TaskManager
from shary.transport.facts import apply_change
from shary.transport.messages import Act, FactChange
from shary.transport.port import MessagePort

if TYPE_CHECKING:
    from shary.team.context import ContextManager

Attachment = Callable[[RobotAgent, Request, Callable[[dict[str, Any]], Any]], Any]
"""What a question of a topic carries, computed when it is asked and handed to the callback
(``{"image": path}``): at once, or when the world that takes the picture replies."""


class AgentLog:
    """A robot's view of the team's context log: rows that name no agent name the robot."""

    __slots__ = ("log", "name")

    def __init__(self, log: Any, name: str):
        self.log = log
        self.name = name

    def record(self, time: float, kind: str, *, task: str | None = None,
               agent: str | None = None, **data: Any) -> int:
        return self.log.record(time, kind, task=task, agent=agent or self.name, **data)


class Team:
    """See the module's docstring."""

    def __init__(self, spec: TeamSpec, *, loop: EventLoop | None = None, log: Any = None,
                 facts: Any = None, executors: dict[str, ExecutorRegistry] | None = None,
                 library: RecipeLibrary | None = None,
                 port: Callable[[EventLoop, Callable[..., None]], MessagePort] | None = None):
        self.spec = spec
        self.loop = loop or EventLoop()
        self.log = log
        if log is not None and hasattr(log, "flush"):
            self.loop.idle_hooks.append(log.flush)
        self.port = (port or MessagePort)(self.loop, self.record)
        """In process unless ``port`` makes another (a ZenohPort: a distributed team)."""
        self.resources = ResourceManager(spec.weights, self.loop.now, self.record)
        self.interaction = InteractionManager(self)
        self.tasks = TaskManager(self, spec.tasks, spec.watchdog)
        self.attachments: dict[str, Attachment] = {}
        """Question topic -> what its questions carry (the weld world attaches a snapshot)."""
        self.agents: dict[str, Agent] = {}
        self._asking: dict[str, AskExecutor] = {}
        robots = spec.of_kind(ROBOT)
        if robots:
            from shary.facts.database import FactDatabase
            from shary.kernel.supervisor import Supervisor
            from shary.team.teamfile import robot_library

            library = library or robot_library(spec)
            facts = facts if facts is not None else FactDatabase()
        self.facts = facts
        """The facts the team's robots and software agents reason on (None without robots);
        what other processes share arrives as ``FactChange`` messages and is applied here."""
        if facts is not None:
            self.port.take(FactChange.kind, lambda change: apply_change(facts, change))
            for axis in ("x", "y"):
                facts.subscribe(self._moved, predicate=axis, kind="added")
        for agent in spec.agents.values():
            if agent.kind == ROBOT:
                sup = Supervisor(library, facts, robot=agent.name, loop=self.loop,
                                 executors=(executors or {}).get(agent.name) or ExecutorRegistry(),
                                 log=AgentLog(log, agent.name) if log is not None else None,
                                 ids=f"{agent.name}/")
                self.agents[agent.name] = RobotAgent(self, agent, sup)
            elif agent.kind == HUMAN:
                self.agents[agent.name] = HumanProxy(self, agent)
            else:
                self.agents[agent.name] = SoftwareAgent(self, agent)
        self.context: ContextManager | None = None
        if log is not None and hasattr(log, "path"):
            from shary.team.context import ContextManager

            self.context = ContextManager(log.path, before=log.flush)
            for agent in self.agents.values():
                if isinstance(agent, SoftwareAgent) and "context" in agent.spec.services:
                    agent.offer("context", self.context.service)

    # -- the log ------------------------------------------------------------------------

    def record(self, kind: str, task: str | None = None, agent: str | None = None,
               **data: Any) -> None:
        """Time-stamp an event of the team into the context log (None values left out)."""
        if self.log is not None:
            self.log.record(self.loop.now(), kind, task=task, agent=agent,
                            **{k: v for k, v in data.items() if v is not None})

    def _moved(self, event: Any) -> None:
        """An agent's perceived ``x`` or ``y`` changed: its position follows (the Resource
        Manager's distance criterion reads it)."""
        agent = self.agents.get(str(event.subject))
        if agent is None or not isinstance(event.object, (int, float)):
            return
        x, y = (agent.position or (0.0, 0.0))[:2]
        agent.position = (event.object, y) if event.predicate == "x" else (x, event.object)

    # -- the members ------------------------------------------------------------------

    def robot(self, name: str) -> RobotAgent:
        agent = self.agents[name]
        if not isinstance(agent, RobotAgent):
            raise KeyError(f"{name} is not a robot of the team")
        return agent

    def human(self, name: str) -> HumanProxy:
        agent = self.agents[name]
        if not isinstance(agent, HumanProxy):
            raise KeyError(f"{name} is not a human of the team")
        return agent

    def own_executor(self, atomic: str, robot: RobotAgent) -> Executor | None:
        """The atomic tasks the team performs for its robots itself (``ask``)."""
        if atomic != "ask":
            return None
        found = self._asking.get(robot.name)
        if found is None:
            found = self._asking[robot.name] = AskExecutor(self, robot)
        return found

    def attach(self, topic: str, attachment: Attachment) -> None:
        """Attach data to the questions of ``topic`` (computed when each is asked)."""
        self.attachments[topic] = attachment

    # -- control authority ---------------------------------------------------------------

    def take_control(self, human: str, robot: str) -> None:
        """``human`` asks to drive ``robot`` (user mode)."""
        self.port.send(Act(human, robot, act=TAKE_CONTROL))

    def hand_back(self, human: str, robot: str) -> None:
        """``human`` gives ``robot`` its autonomy back (system mode)."""
        self.port.send(Act(human, robot, act=HAND_BACK))

    def teleoperate(self, human: str, robot: str, atomic: str, args: dict[str, Any]) -> None:
        """``human``, in control of ``robot``, sends it one atomic task."""
        self.port.send(Act(human, robot, act=TELEOPERATE, data={"atomic": atomic,
                                                                "args": dict(args)}))

    # -- a member killed ----------------------------------------------------------------

    def kill(self, name: str) -> None:
        """``name``'s process dies, in this process: it falls silent (the port drops what
        it sends and what is sent to it, :attr:`MessagePort.down`), and the managers
        react as a distributed team's conductor makes them react to a lost liveliness
        token (:mod:`shary.transport.distributed`): the Task Manager takes back the task
        it was offered or ran (``agent-lost``) and the Interaction Manager reroutes the
        questions it held and the help it gave; a robot it was driving is in system
        mode again (its own goals go on: nobody is left to hand it back)."""
        self.record("agent-killed", agent=name)
        self.port.down.add(name)
        self.tasks.agent_lost(name)
        self.interaction.agent_lost(name)
        for agent in self.agents.values():  # an operator gone hands nothing back: take it
            if getattr(agent, "controller", None) == name:
                agent.hand_back(name)

    # -- running ------------------------------------------------------------------------

    def start(self) -> None:
        """Start the goal and the people's own scripts (once: later calls do nothing)."""
        if self.tasks.started:
            return
        self.tasks.start()
        for agent in self.agents.values():
            if isinstance(agent, HumanProxy):
                agent.start_script()

    def run(self, limit: float, *, step: float = 5.0) -> str | None:
        """Simulated time: start, then advance until the goal is over or ``limit`` seconds
        have passed; the goal's outcome ("done", "failed") or None."""
        self.start()
        end = self.loop.now() + limit
        while self.tasks.outcome is None and self.loop.now() < end:
            self.loop.advance(min(step, end - self.loop.now()))
        return self.tasks.outcome

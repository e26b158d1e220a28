"""The simulated Jido behind ROS 2: ``shary world --ros SCENARIO``.

The PyBullet living room of a scenario (its robot, objects and people, as
:func:`sim.run.run_scenario` builds them) runs in real time as a ROS 2 robot
that serves the interfaces of the Jido binding (``shary/ros/bindings/
jido-sim.yaml``), so that a supervisor in another process (``shary run
SCENARIO --ros``, :mod:`sim.rosrun`) reaches it only through ROS 2:

- each atomic task bound to an action is served: the goal's numbers are turned
  back into the task's parameters with the binding's ``codes:``, the robot's
  executor (:class:`sim.executors.RobotExecutors`) performs it, and the result
  says whether it succeeded (``bool_value``); a cancel stops it where it is;
- what the robot says arrives on the binding's speech topic (``/jido/say``):
  the robot says it, and the people answer once it has finished;
- the robot's perception (:class:`sim.perception.Perception`, with what it
  knows beforehand) is published as lines ``SUBJECT PREDICATE OBJECT`` on the
  binding's fact topic, whole, on every change and at least every second;
- the people hear the supervisor's acts on ``/shary/acts`` (who is asked what,
  in which task) and answer on ``/shary/person_act``; in a shared-plan scenario
  (``stack-*``) the partner follows the supervisor's plan as ``/shary/plan``
  tells it (each task due, started, done); what they say of their
  own accord (a request) goes on the binding's speech-in topic
  (``/jido/heard/NAME``), to the supervisor's requests grammar.

Only this module and :mod:`sim.rosrun` of ``sim`` touch ROS, and only through
:mod:`shary.ros` (which alone imports rclpy).  The world's clock is the
simulation's, kept in step with the wall clock.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from rdflib import Literal

from shary.facts import FactDatabase
from shary.loop import EventLoop

from .executors import RobotExecutors
from .people import Person
from .perception import Noise, Perception
from .run import a_priori, arrange_objects
from .scenario import load_scenario
from .simulation import Simulation
from .stack.session import StackSession
from .world import LivingRoom

JIDO_BINDING = Path(__file__).resolve().parent.parent / "shary" / "ros" / "bindings" / \
    "jido-sim.yaml"
STEP = 0.02
"""Wall seconds between two steps of the world (it advances by the time that passed)."""
REPUBLISH = 1.0
"""Seconds after which the robot's facts are published again though unchanged (the
binding's fact topic goes stale after 2 s of silence)."""
SUPERVISOR = "/shary"
"""The supervisor's node, whose ``acts`` and ``person_act`` topics the people use."""


class _Request:
    """An atomic task the world's executors perform for a goal (what they read of it)."""

    def __init__(self, rid: str, atomic: str, args: dict[str, Any], agent: str):
        self.id, self.atomic, self.args, self.agent, self.node = rid, atomic, args, agent, rid


class _Goal:
    """How one goal ends, told to the action server's coroutine on the executor's thread."""

    def __init__(self, node: Any, future: Any):
        self.node, self.future = node, future
        self.request: _Request | None = None

    def done(self, request: Any) -> None:
        self._end("succeeded", "")

    def failed(self, request: Any, reason: str) -> None:
        self._end("failed", reason)

    def cancelled(self, request: Any, reason: str) -> None:
        self._end("canceled", reason)

    def _end(self, outcome: str, reason: str) -> None:
        if not self.future.done():
            self.node.post(_settle, self.future, (outcome, reason))


def _settle(future: Any, value: Any) -> None:
    if not future.done():
        future.set_result(value)


class _Run:
    """A supervisor's task as the people see it on ``/shary/acts`` (what
    :meth:`sim.people.Person.on_act` reads of a task run)."""

    def __init__(self, data: dict[str, Any]):
        self.node = str(data["node"])
        self.roles = {str(k): str(v) for k, v in (data.get("roles") or {}).items()}
        self.env = dict(data.get("env") or {})
        self.ended = False


class _State:
    def __init__(self, act: str):
        self.act = act


class _Supervisor:
    """The supervisor as the simulated people reach it: over ROS 2 (see the module's
    docstring)."""

    def __init__(self, world: RosWorld):
        self.world = world
        self.dialogue = self

    def receive_act(self, agent: str, act: str, data: Any = None,
                    task: str | None = None) -> None:
        self.world.send_act(agent, act, data, task)

    def hear(self, agent: str, sentence: str) -> None:
        self.world.send_speech(agent, sentence)

    def record(self, kind: str, **data: Any) -> None:
        """The people's own actions are the world's business, not the supervisor's log."""


class RosWorld:
    """A scenario's living room served over ROS 2 (see the module's docstring)."""

    def __init__(self, path: str | Path, world: LivingRoom, node: Any, binding: Any,
                 *, seed: int = 0, report: Any = None):
        from std_msgs.msg import String

        from shary.ros.binding import import_interface

        self.scenario = scenario = load_scenario(path)
        self.stack = StackSession(scenario.shared_plan, scenario.robot) \
            if scenario.shared_plan else None
        self.world, self.node, self.binding = world, node, binding
        self.report = report or (lambda t, who, kind, text: None)
        self.loop = EventLoop(seed=seed)
        self.facts = FactDatabase()
        robot = scenario.robot
        world.add_robot(robot, scenario.model, scenario.robot_at)
        self.sim = Simulation(world, self.loop, robot)
        self.executors = (self.stack.executors_class if self.stack else RobotExecutors)(
            self.sim, self.say, self.facts.set,
                                        lambda who, kind, text: self.report(
                                            self.loop.now(), who, kind, text))
        self.supervisor = _Supervisor(self)
        self.people: dict[str, Person] = {}
        for spec in scenario.people:
            self.sim.add_person(spec.name, spec.at, (*spec.shirt, 1.0))
            person = Person(spec.name, spec.profile, self.sim, self.supervisor,
                            self.loop.random, self.executors, self.say)
            self.people[spec.name] = person
            self.sim.tick_hooks.append(person.refresh)
        self.executors.people = self.people
        for action, reason, times in scenario.faults:
            self.executors.faults.setdefault(action, []).extend([reason] * times)
        arrange_objects(world, self.sim, scenario, self.stack)
        a_priori(self.facts, world, scenario, self.stack)
        self.perception = (self.stack.perception_class if self.stack else Perception)(
            self.sim, self.facts, hold=scenario.hold,
                                     noise=Noise(dict(scenario.flicker), list(scenario.lost)),
                                     rng=self.loop.random)
        self.sim.observers.append(self.perception.update)
        self.runs: dict[str, _Run] = {}
        self._goals = 0
        self._published: str | None = None
        self._published_at = -REPUBLISH
        # -- the binding's interfaces -------------------------------------------------
        self.codes = {code: name for name, code in binding.codes.items()}
        for atomic, task in binding.tasks.items():
            if task.kind == "action":
                node.action_server(import_interface(task.type), task.name,
                                   **self._callbacks(atomic, task))
            elif atomic == "speak":
                node.subscription(import_interface(task.type), task.name,
                                  lambda m: node.put(self.speak, str(m.data)))
        self.fact_pub = node.publisher(String, binding.facts[0].topic)
        self.speech_pubs = {s.speaker: node.publisher(String, s.topic) for s in binding.speech}
        self.act_pub = node.publisher(String, f"{SUPERVISOR}/person_act", depth=100)
        node.subscription(String, f"{SUPERVISOR}/acts", lambda m: node.put(self.on_act, m.data))
        self.follower = _Follower()
        if self.stack is not None:  # the partner follows the supervisor's shared plan
            self.stack.join(self.people[self.stack.partner_name], self.follower)
            node.subscription(String, f"{SUPERVISOR}/plan",
                              lambda m: node.put(self.follower.hear, m.data))

    # -- goals (the callbacks run on the executor's thread; the work on the world's) -----

    def _callbacks(self, atomic: str, task: Any) -> dict[str, Any]:
        from rclpy.action import CancelResponse
        from rclpy.task import Future

        cls = self._interface(task)
        live: dict[bytes, _Goal] = {}
        """A goal's id -> how it ends, while it runs."""

        async def execute(handle: Any) -> Any:
            key = bytes(handle.goal_id.uuid)
            goal = live[key] = _Goal(self.node, Future())
            self.node.put(self.start, atomic, task, handle.request, goal)
            outcome, reason = await goal.future
            del live[key]
            result = cls.Result()
            result.nested_field.bool_value = outcome == "succeeded"
            result.nested_field.int32_value = 0 if outcome == "succeeded" else 1
            if outcome == "canceled" and handle.is_cancel_requested:
                handle.canceled()
            else:
                handle.succeed()
            return result

        def cancel(handle: Any) -> Any:
            goal = live.get(bytes(handle.goal_id.uuid))
            if goal is not None:
                self.node.put(self.cancel, goal)
            return CancelResponse.ACCEPT

        return {"execute_callback": execute, "cancel_callback": cancel}

    @staticmethod
    def _interface(task: Any) -> Any:
        from shary.ros.binding import import_interface

        return import_interface(task.type)

    def start(self, atomic: str, task: Any, message: Any, goal: _Goal) -> None:
        """Perform ``atomic`` for a goal (on the world's thread)."""
        from shary.ros.messages import read_field

        args: dict[str, Any] = {}
        for field, template in task.goal.items():
            if not (isinstance(template, str) and template.startswith("{")):
                continue
            name = template.strip("{}")
            value = read_field(message, field)
            if name.startswith("code:"):
                name = name[len("code:"):]
                value = self.codes.get(int(value or 0))
            if value is not None:
                args[name] = value
        self._goals += 1
        goal.request = _Request(f"g{self._goals}", atomic, args, self.scenario.robot)
        self.executors.start(goal.request, goal)

    def cancel(self, goal: _Goal) -> None:
        if goal.request is not None:
            self.executors.cancel(goal.request)

    def speak(self, text: str) -> None:
        """The supervisor said ``text`` (on the speech topic): the robot says it."""
        self._goals += 1
        request = _Request(f"g{self._goals}", "speak", {"text": text}, self.scenario.robot)
        self.executors.start(request, _Goal(self.node, _Done()))

    # -- the people ------------------------------------------------------------------------

    def on_act(self, text: str) -> None:
        """An act of the supervisor's began (or a task ended): the people may answer."""
        data = json.loads(text)
        if "ended" in data:
            run = self.runs.pop(str(data["ended"]), None)
            if run is not None:
                run.ended = True
            return
        run = self.runs.setdefault(str(data["node"]), _Run(data))
        run.env = dict(data.get("env") or {})
        for person in self.people.values():
            person.on_act(run, _State(str(data["act"])), str(data.get("agent")))

    def send_act(self, agent: str, act: str, data: Any, task: str | None) -> None:
        from std_msgs.msg import String

        message = {"agent": agent, "act": act, "data": data, "task": task}
        self.node.post(self.act_pub.publish, String(data=json.dumps(message)))

    def send_speech(self, agent: str, sentence: str) -> None:
        from std_msgs.msg import String

        publisher = self.speech_pubs.get(agent)
        if publisher is not None:
            self.node.post(publisher.publish, String(data=sentence))

    def say(self, who: str, text: str) -> None:
        self.report(self.loop.now(), who, "speech", text)

    # -- perception out, and the clock -------------------------------------------------

    def publish_facts(self, wall: float) -> None:
        from std_msgs.msg import String

        lines = "\n".join(sorted(f"{s} {p} {_literal(o)}"
                                 for s, p, o in self.facts.triples("robot")))
        if lines != self._published or wall - self._published_at >= REPUBLISH:
            self._published, self._published_at = lines, wall
            self.node.post(self.fact_pub.publish, String(data=lines))

    def serve(self, seconds: float | None = None, stopping: list[int] | None = None) -> None:
        """Run the world in step with the wall clock (until ``seconds`` or ``stopping``)."""
        for person in self.people.values():
            person.begin()
        self.perception.start()
        origin = time.monotonic()
        while not stopping and (seconds is None or self.loop.now() < seconds):
            self.node.drain()
            wall = time.monotonic() - origin
            if wall > self.loop.now():
                self.loop.advance(wall - self.loop.now())
            self.publish_facts(wall)
            time.sleep(STEP)


class _Task:
    """A task of the shared plan as the partner reads it: its label."""

    def __init__(self, label: str):
        self._label = label

    def label(self) -> str:
        return self._label


class _Plan:
    def __init__(self) -> None:
        self.primitive: dict[int, _Task] = {}


class _Follower:
    """The supervisor's plan follower as the partner (:class:`sim.stack.partner.
    StackPartner`) sees it, from ``/shary/plan``: the plan's tasks, the ones due now,
    whether it is over, and each event told to the watchers."""

    def __init__(self) -> None:
        self.plan = _Plan()
        self.current: list[int] = []
        self.finished: str | None = None
        self.watchers: list[Any] = []

    def hear(self, text: str) -> None:
        data = json.loads(text)
        self.plan.primitive = {int(k): _Task(str(v)) for k, v in data["labels"].items()}
        self.current = [int(t) for t in data["current"]]
        self.finished = data.get("finished")
        for watcher in self.watchers:
            watcher(str(data["event"]), int(data["task"]))


class _Done:
    """The future of a goal nobody waits for (the robot's speech, a topic)."""

    def done(self) -> bool:
        return True


def _literal(value: Any) -> str:
    """A fact's object as a line carries it: numbers, truth values and text literals (a
    position "X Y Z") as JSON writes them (the supervisor's perception reads them back as
    such), a name as it is."""
    if isinstance(value, (bool, int, float, Literal)):
        return json.dumps(value if not isinstance(value, Literal) else str(value))
    return str(value)

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
  (``/jido/heard/NAME``), to the supervisor's requests grammar;
- whether anything is left to happen in the world goes on ``/jido_sim/quiet``, so
  that the supervisor knows when the run is over (a person may still be on their
  way to do something).

Objects and people a scenario adds get codes after the binding's, the same in both
processes (:func:`scenario_binding`).

Only this module and :mod:`sim.rosrun` of ``sim`` touch ROS, and only through
:mod:`shary.ros` (which alone imports rclpy).  The world's clock is the
simulation's, kept in step with the wall clock from when a supervisor is there;
a world serves one run: it stops when its supervisor leaves (start another for
the next).
"""

from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path
from typing import Any

from rdflib import Literal

from shary.facts.database import FactDatabase
from shary.kernel.loop import EventLoop

from .executors import RobotExecutors
from .run import furnish
from .scenario import load_scenario
from .simulation import Simulation
from .stack.session import StackSession
from .world import LivingRoom

JIDO_BINDING = Path(__file__).resolve().parent.parent / "shary" / "ros" / "bindings" / \
    "jido-sim.yaml"
STEP = 0.02
"""Wall seconds between two steps of the world (it advances by the time that passed)."""
WAITING = 0.1
"""Wall seconds between two looks for a supervisor, before the scenario starts."""
STILL_THERE = 0.5
"""Wall seconds between two looks at whether the supervisor is still there, once the
scenario has started (a world serves one run: it stops when its supervisor leaves)."""
REPUBLISH = 1.0
"""Seconds after which the robot's facts are published again though unchanged (the
binding's fact topic goes stale after 2 s of silence)."""
FAILURE_CODE = "nested_field.int32_value"
"""The field of the jido-sim binding's results that carries a failure's code."""
LEASE = 0.5
"""Seconds of the liveliness lease the robot's fact topic offers: a supervisor that asks
for a lease at least this long (the binding's ``alive:``) notices the world gone within
it (:mod:`shary.ros.liveliness`)."""
QUIET = "/jido_sim/quiet"
"""Where the world says whether anything is left to happen in it (``std_msgs/Bool``)."""
SUPERVISOR = "/shary"
"""The supervisor's node, whose ``acts`` and ``person_act`` topics the people use."""


class _Request:
    """An atomic task the world's executors perform for a goal (what they read of it)."""

    def __init__(self, rid: str, atomic: str, args: dict[str, Any], agent: str):
        self.id, self.atomic, self.args, self.agent, self.node = rid, atomic, args, agent, rid


class _Goal:
    """A goal the world performs, and how it ends: told to the action server through
    ``end`` (:meth:`shary.ros.node.RosNode.serve_goals`) as the binding's result."""

    def __init__(self, result: Any, task: Any, end: Any):
        self.result, self.task, self._end = result, task, end
        self.request: _Request | None = None
        self.over = False

    def done(self, request: Any) -> None:
        self._finish(True, False)

    def failed(self, request: Any, reason: str) -> None:
        self._finish(False, False)

    def cancelled(self, request: Any, reason: str) -> None:
        self._finish(False, True)

    def _finish(self, succeeded: bool, canceled: bool) -> None:
        from shary.ros.messages import build

        if self.over or self.result is None:  # ended, or speech: nobody waits for a result
            self.over = True
            return
        self.over = True
        # the binding's succeeded-if fields say whether it worked, FAILURE_CODE why not
        fields = {f: v if succeeded else not v for f, v in self.task.succeeded_if.items()}
        if not succeeded:
            fields[FAILURE_CODE] = 1
        self._end(build(self.result, fields, {}, codes={}), canceled)


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
        from std_msgs.msg import Bool, String

        from shary.ros.binding import import_interface

        self.scenario = scenario = load_scenario(path)
        binding = scenario_binding(binding, scenario)
        self.stack = StackSession(scenario.shared_plan, scenario.robot) \
            if scenario.shared_plan else None
        self.world, self.node, self.binding = world, node, binding
        self.report = report or (lambda t, who, kind, text: None)
        self.loop = EventLoop(seed=seed)
        node.attach(self.loop)  # what comes over ROS 2 runs on the world's loop
        self.facts = FactDatabase()
        robot = scenario.robot
        world.add_robot(robot, scenario.model, scenario.robot_at)
        self.sim = Simulation(world, self.loop, robot)
        self.executors = (self.stack.executors_class if self.stack else RobotExecutors)(
            self.sim, self.say, self.facts.set,
            lambda who, kind, text: self.report(self.loop.now(), who, kind, text))
        self.supervisor = _Supervisor(self)
        self.people, self.perception = furnish(
            world, self.sim, scenario, self.stack, self.facts, self.executors,
            self.supervisor, self.say)
        self.runs: dict[str, _Run] = {}
        self.goals: dict[bytes, _Goal] = {}
        self._goals = 0
        self._published: str | None = None
        self._published_at = -REPUBLISH
        # -- the binding's interfaces -------------------------------------------------
        self.codes = {code: name for name, code in binding.codes.items()}
        for atomic, task in binding.tasks.items():
            if task.kind == "action":
                node.serve_goals(import_interface(task.type), task.name,
                                 lambda key, goal, end, a=atomic, t=task:
                                     self.start(a, t, key, goal, end), self.cancel)
            elif atomic == "speak":
                node.subscription(import_interface(task.type), task.name,
                                  lambda m: node.put(self.speak, str(m.data)))
        self.fact_pub = node.publisher(String, binding.facts[0].topic, lease=LEASE)
        self.quiet_pub = node.publisher(Bool, QUIET)
        self._quiet: bool | None = None
        self.speech_pubs = {s.speaker: node.publisher(String, s.topic) for s in binding.speech}
        self.act_pub = node.publisher(String, f"{SUPERVISOR}/person_act", depth=100)
        node.subscription(String, f"{SUPERVISOR}/acts", lambda m: node.put(self.on_act, m.data))
        self.follower = _Follower()
        if self.stack is not None:  # the partner follows the supervisor's shared plan
            self.stack.join(self.people[self.stack.partner_name], self.follower)
            node.subscription(String, f"{SUPERVISOR}/plan",
                              lambda m: node.put(self.follower.hear, m.data))

    # -- goals (rclpy's callbacks put them on the world's loop) -------------------------

    def start(self, atomic: str, task: Any, key: bytes, message: Any, end: Any) -> None:
        """Perform ``atomic`` for a goal (on the world's loop)."""
        from shary.ros.binding import import_interface
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
        goal = self.goals[key] = _Goal(import_interface(task.type).Result, task, end)
        goal.request = _Request(f"g{self._goals}", atomic, args, self.scenario.robot)
        self.executors.start(goal.request, goal)

    def cancel(self, key: bytes) -> None:
        goal = self.goals.get(key)
        if goal is not None and goal.request is not None and not goal.over:
            self.executors.cancel(goal.request)

    def speak(self, text: str) -> None:
        """The supervisor said ``text`` (on the speech topic): the robot says it."""
        self._goals += 1
        request = _Request(f"g{self._goals}", "speak", {"text": text}, self.scenario.robot)
        self.executors.start(request, _Goal(None, None, None))

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
        self.act_pub.publish(String(data=json.dumps(message)))

    def send_speech(self, agent: str, sentence: str) -> None:
        from std_msgs.msg import String

        publisher = self.speech_pubs.get(agent)
        if publisher is not None:
            publisher.publish(String(data=sentence))

    def say(self, who: str, text: str, request: str | None = None) -> None:
        """``who`` says ``text``: told to the run's story (the robot's own sentences are
        logged by its ROS executors, as it sends them)."""
        self.report(self.loop.now(), who, "speech", text)

    # -- perception out, and the clock -------------------------------------------------

    @property
    def quiet(self) -> bool:
        """Whether nothing is left to happen in the world (no motion, no timer, no person
        with something to do): with the supervisor's own, the end of a run."""
        return (not self.sim.busy and self.loop.clock.next_due() is None
                and not any(p.pending for p in self.people.values()))

    def publish(self, wall: float) -> None:
        """The robot's facts and whether the world is quiet: on change, and every
        :data:`REPUBLISH` seconds."""
        from std_msgs.msg import Bool, String

        again = wall - self._published_at >= REPUBLISH
        if self.quiet != self._quiet or again:
            self._quiet = self.quiet
            self.quiet_pub.publish(Bool(data=self._quiet))
        lines = "\n".join(sorted(f"{s} {p} {_literal(o)}"
                                 for s, p, o in self.facts.triples("robot")))
        if lines != self._published or again:
            self._published, self._published_at = lines, wall
            self.fact_pub.publish(String(data=lines))

    def supervised(self) -> bool:
        """Whether a supervisor listens to the people (its ``person_act`` subscription)."""
        return bool(self.act_pub.get_subscription_count())

    def serve(self, seconds: float | None = None, stopping: list[int] | None = None,
              starting: Any = None) -> bool:
        """Run the world in step with the wall clock, from when a supervisor is there
        (``starting()`` is told) until ``seconds``, ``stopping``, or the supervisor
        leaves (True: a world serves one run, its scenario played once; the next run
        needs a world of its own).  Until then the world's clock waits, publishing
        what the robot knows: in one process the people and the supervisor start
        together, and a person's first request must not go out before anyone
        listens."""
        stopping = stopping if stopping is not None else []
        for person in self.people.values():  # who looks where at the start, as perceived
            person.refresh()
        self.perception.start()
        while not stopping and not self.supervised():
            self.loop.run_until_idle()
            self.publish(time.monotonic())
            self.node.spin_for(WAITING)
        if stopping:
            return False
        if starting is not None:
            starting()
        for person in self.people.values():
            person.begin()
        origin = looked = time.monotonic()
        while not stopping and (seconds is None or self.loop.now() < seconds):
            self.loop.run_until_idle()
            wall = time.monotonic() - origin
            if wall > self.loop.now():
                self.loop.advance(wall - self.loop.now())
            self.publish(time.monotonic())
            if time.monotonic() - looked >= STILL_THERE:
                looked = time.monotonic()
                if not self.supervised():
                    return True
            self.node.spin_for(STEP)
        return False


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


def scenario_binding(binding: Any, scenario: Any) -> Any:
    """The Jido binding for one scenario, the same in both processes: the scenario's
    robot, and a code for each object and person the scenario adds (after the binding's
    codes, in name order)."""
    codes = dict(binding.codes)
    added = set(scenario.objects) | {p.name for p in scenario.people}
    if scenario.shared_plan:
        added |= set(StackSession.objects())
    first = max(codes.values(), default=0) + 1
    codes.update({name: first + i for i, name in enumerate(sorted(added - set(codes)))})
    return dataclasses.replace(binding, robot=scenario.robot, codes=codes)


def _literal(value: Any) -> str:
    """A fact's object as a line carries it: numbers, truth values and text literals (a
    position "X Y Z") as JSON writes them (the supervisor's perception reads them back as
    such), a name as it is."""
    if isinstance(value, (bool, int, float, Literal)):
        return json.dumps(value if not isinstance(value, Literal) else str(value))
    return str(value)

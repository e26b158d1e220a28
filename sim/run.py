"""Running a scenario end to end: world, people, perception, supervisor, judge, files.

Times reported: ``simulated_seconds`` (the engine clock at the end),
``wall_seconds`` (the simulation proper, once the files are read and the world
built), ``setup_seconds`` (building the world, the people, the supervisor);
the real-time factor is simulated over wall seconds.

:func:`run_scenario` builds the living room and the scenario's people, fills
the supervisor's ports (executors, perception into the fact database, the
living-room planner, act listeners for the people), seeds the robot's
a-priori knowledge (types and the planner's static attributes), adds the
goals, and advances the one event loop until nothing is left to happen (no
task, goal, motion or timer) or the timeout.  Then it judges the outcome
against the scenario and writes, to the output folder: ``log.sqlite`` (the
context log), ``tree.svg`` (the final task tree), ``timeline.svg`` (a lane per
agent), ``summary.json``, and with ``snapshots`` PNG views at each act.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import planner
from shary.dialogue.sessions import Sessions
from shary.facts.database import FactDatabase
from shary.kernel.agenda import OVER, ChronicleRecognizer
from shary.kernel.executors import ExecutorRegistry
from shary.kernel.loop import EventLoop
from shary.kernel.planning import HatpPlanner
from shary.kernel.supervisor import Supervisor
from shary.log.contextlog import ContextLog, read_events
from shary.log.told import Told
from shary.recognition.models import load_action_models
from userfiles.outputs import output_folder, write_output

from .executors import RobotExecutors
from .judge import Happened, judge
from .narration import Narrator, Report
from .objects import is_new, new_object
from .people import Person
from .perception import Noise, Perception
from .results import CHUNK, MemoryLog, RunResult
from .scenario import Scenario, is_team_scenario, load_scenario
from .simulation import Simulation, standing_height
from .stack.session import StackSession
from .world import (
    BOTTLES,
    CONTAINERS,
    FURNITURE,
    MANIPULATION_PLACES,
    SEATS,
    LivingRoom,
    framing,
    pb,
)

ROBOT_ATTRIBUTES = {"kind": "robot", "move_cost": 2, "pick_cost": 1, "speed": 1}
SNAPSHOT_SIZE = (800, 600)
"""Snapshots' size in pixels, caption included: large enough to see a head turn
away.  The software renderer takes about 0.75 s for one, 3.3 times the former
480 x 360 (1.16 s at 960 x 720), measured in one run."""
PERSON_ATTRIBUTES = {"kind": "human", "move_cost": 4, "pick_cost": 2, "speed": 1}


def load(path: str | Path) -> tuple[Scenario, Any, Any]:
    """A scenario checked with the recipe library it will run with, that library, and
    the planning domain its planner-backed recipes use (every file is read before the run)."""
    scenario = load_scenario(path)
    return scenario, scenario.library, planner.load_domain("living-room")


def run_scenario(path: str | Path | Scenario | Any, *, seed: int = 0,
                 out: str | Path | None = None, snapshots: bool = False, gui: bool = False,
                 report: Report | None = None, console: Any = None) -> RunResult:
    """Run one scenario (see the module's docstring); ``report`` is told the story as it
    happens (see :mod:`sim.narration`; :class:`sim.narration.ConsoleReport` prints it).
    ``console`` (a :class:`shary.console.live.Attachment`) is given the supervisor, sees
    every logged event, and is called between two steps of the clock (pause, speed).
    A team scenario (``site: seam-welding``) runs on its site (:mod:`sim.weld.run`),
    without a console for now.  ``path`` may also be a scenario already loaded (a
    :class:`~sim.scenario.Scenario` or a :class:`~sim.weld.scenario.WeldScenario`)."""
    from .weld.scenario import WeldScenario

    if isinstance(path, WeldScenario) or (not isinstance(path, Scenario)
                                          and is_team_scenario(path)):
        from .weld.run import run_weld

        return run_weld(path, seed=seed, out=out, snapshots=snapshots, gui=gui, report=report)
    if isinstance(path, Scenario):
        scenario, library, domain = path, path.library, planner.load_domain("living-room")
    else:
        scenario, library, domain = load(path)
    out_dir = Path(out) if out is not None else None
    log_path = fresh_folder(out_dir) if out_dir is not None else None
    wall = time.perf_counter()
    with LivingRoom(gui=gui, robot=None) as world, \
            _log(log_path, seed) as log:
        run = _Run(scenario, library, domain, world, log, seed,
                   report or (lambda t, who, kind, text: None), out_dir if snapshots else None,
                   console)
        setup = time.perf_counter() - wall
        wall = time.perf_counter()
        end = run.go()
        wall = time.perf_counter() - wall
        differences = judge(scenario.expect, run.happened(end, log_path))
        if end >= scenario.timeout - 1e-9:
            differences.append(f"the run was still going at the timeout ({scenario.timeout:g}s)")
        result = RunResult(scenario.name, not differences, differences, end, wall, setup, seed,
                           run.sim.physics_steps, run.perception.misses,
                           events=log.events if out_dir is None else [],
                           truth=run.truth)
        if out_dir is not None and log_path is not None:
            log.flush()
            result.outputs = draw(run.sup.tree, log_path, out_dir, scenario.name)
            if run.snapshots:
                result.outputs["snapshots"] = ", ".join(str(out_dir / n) for n in run.snapshots)
            write_summary(result, out_dir)
    return result


def fresh_folder(out_dir: Path) -> Path:
    """Check ``out_dir`` as a run's folder and take away what an earlier run left there
    that this one may not write again (its log, its snapshots), so that the folder holds
    one run; the path of the new log.  Every run of a living-room scenario, in one
    process or over ROS 2, starts here."""
    output_folder(out_dir)
    for stale in out_dir.glob("snapshot-*.png"):
        stale.unlink()
    log_path = out_dir / "log.sqlite"
    if log_path.exists():
        log_path.unlink()
    return log_path


def draw(tree: Any, log_path: Path, out_dir: Path, name: str) -> dict[str, str]:
    """The run's final task tree and its timeline, drawn beside its log: the files of every
    run's folder (their paths, the log's included)."""
    from shary.log.display import render_tree
    from shary.log.timeline import write_timeline

    render_tree(tree, out_dir / "tree.svg", title=f"{name}: task tree")
    write_timeline(log_path, out_dir / "timeline.svg", title=name)
    return {"log": str(log_path), "tree": str(out_dir / "tree.svg"),
            "timeline": str(out_dir / "timeline.svg")}


def write_summary(result: RunResult, out_dir: Path) -> None:
    """``summary.json``, one shape for every run (docs/cli.md), added to its outputs."""
    result.outputs["summary"] = str(out_dir / "summary.json")
    write_output(out_dir / "summary.json", json.dumps(result.summary(), indent=2) + "\n")


def _log(path: Path | None, seed: int) -> Any:
    return ContextLog(path, seed=seed) if path is not None else MemoryLog()


def furnish(world: LivingRoom, sim: Simulation, scenario: Scenario,
            stack: StackSession | None, facts: FactDatabase, executors: Any,
            supervisor: Any, say: Callable[[str, str], None],
            ) -> tuple[dict[str, Person], Perception]:
    """Put the scenario's people, faults and objects in the room, the a-priori facts in
    ``facts``, and the robot's perception on the simulation: what a run in one process
    and the world served over ROS 2 (:mod:`sim.rosworld`) both set up.  ``supervisor``
    is what the people answer (the engine, or its stand-in across ROS)."""
    people: dict[str, Person] = {}
    for spec in scenario.people:
        sim.add_person(spec.name, spec.at, (*spec.shirt, 1.0))
        person = Person(spec.name, spec.profile, sim, supervisor, sim.loop.random,
                        executors, say)
        people[spec.name] = person
        sim.tick_hooks.append(person.refresh)
    executors.people = people
    for action, reason, times in scenario.faults:
        executors.faults.setdefault(action, []).extend([reason] * times)
    arrange_objects(world, sim, scenario, stack)
    a_priori(facts, world, scenario, stack)
    perception = (stack.perception_class if stack else Perception)(
        sim, facts, hold=scenario.hold,
        noise=Noise(dict(scenario.flicker), list(scenario.lost)), rng=sim.loop.random)
    sim.observers.append(perception.update)
    return people, perception


def arrange_objects(world: LivingRoom, sim: Simulation, scenario: Scenario,
                    stack: StackSession | None) -> None:
    """Add the scenario's new objects to the room, and put every object in its place."""
    objects = {**(stack.objects() if stack else {}), **scenario.objects}
    for obj, spec in objects.items():
        furniture = spec.get("on", "coffee-table")
        f = world.footprints[furniture]
        x, y = spec.get("at", (f.x, f.y))
        if is_new(spec):
            world.add_object(new_object(obj, spec), x, y, world.top(furniture))
        if "held-by" in spec:
            sim.attach(obj, spec["held-by"])
            continue
        z = standing_height(world.top(furniture), world.sizes[obj][0])
        world.call(pb.resetBasePositionAndOrientation, world.body(obj), [x, y, z], [0, 0, 0, 1])


def a_priori(facts: FactDatabase, world: LivingRoom, scenario: Scenario,
             stack: StackSession | None) -> None:
    """What the robot knows before it looks: kinds of things, the planner's constants."""
    robot = scenario.robot
    for place in world.places:
        facts.add(place, "type", "Place")
    for furniture in FURNITURE:
        facts.add(furniture, "type", "Furniture")
        # its own kind too ("coffee-table" is a CoffeeTable): what people call it
        facts.add(furniture, "type", "".join(
            w.title() for w in furniture.split("-") if not w.isdigit()))
        if furniture in MANIPULATION_PLACES:  # the others the robot cannot reach
            facts.add(furniture, "place", MANIPULATION_PLACES[furniture])
        facts.add(furniture, "container", furniture in CONTAINERS)
        facts.add(furniture, "seat", furniture in SEATS)
    for obj in BOTTLES:
        facts.add(obj, "type", "Object")
        facts.add(obj, "type", "Bottle")
        facts.add(obj, "color", obj.split("-")[0])
        facts.add(obj, "drink", True)
        facts.add(obj, "robot_reach", True)
    for added in world.added.values():
        facts.add(added.name, "type", "Object")
        facts.add(added.name, "type", added.kind[:1].upper() + added.kind[1:])
        facts.add(added.name, "color", added.colour)
        facts.add(added.name, "shape", added.shape)
        facts.add(added.name, "drink", False)
        facts.add(added.name, "robot_reach", True)
    facts.add(robot, "type", "Agent")
    facts.add(robot, "type", "Robot")
    for attribute, value in ROBOT_ATTRIBUTES.items():
        facts.add(robot, attribute, value)
    if stack is not None:
        stack.a_priori(facts)
    for spec in scenario.people:
        facts.add(spec.name, "type", "Agent")
        facts.add(spec.name, "type", "Human")
        for attribute, value in {**PERSON_ATTRIBUTES, **spec.attributes}.items():
            facts.add(spec.name, attribute, value)


def happened(events: list[tuple[float, str, Any, Any, dict[str, Any]]], facts: FactDatabase,
             robot: str, end: float) -> Happened:
    """What a run's logged events and the robot's final beliefs say happened (judged
    against a scenario's expectations)."""
    acts, actions, tasks = [], [], {}
    plan, said, task_states, recognized = [], [], set(), []
    requests: dict[str, tuple[str, str]] = {}
    for t, kind, _, agent, data in events:
        if kind == "shared-plan":
            plan.append(data["state"])
        elif kind == "speech" and agent == robot:
            said.append(data["text"])
        elif kind == "plan-task":
            task_states.add((agent or "", data["name"], data["state"]))
        elif kind == "recognition":
            recognized.append((data["state"], data["action"], agent or ""))
        if kind == "act":
            acts.append((t, agent or "", data["act"]))
        elif kind == "act-received":
            acts.append((t, agent or "", data["act"]))
        elif kind == "exec-request":
            requests[data["request"]] = (agent or "", data["atomic"])
            actions.append((t, agent or "", data["atomic"], "started"))
        elif kind == "exec-result" and data["request"] in requests:
            who, atomic = requests[data["request"]]
            actions.append((t, who, atomic, data["status"]))
        elif kind == "task-end":
            tasks.setdefault(data["name"], []).append(data.get("outcome", "done"))
    believed = {(str(s), str(p), str(o)) for s, p, o in facts.triples("robot")}
    return Happened(acts, actions, tasks, believed, end, plan, said, task_states, recognized)


class _Run:
    """One run's parts, wired together."""

    def __init__(self, scenario: Scenario, library: Any, domain: Any, world: LivingRoom,
                 log: Any, seed: int, report: Report,
                 snapshot_dir: Path | None, console: Any = None):
        self.scenario = scenario
        self.world = world
        self.log = log
        self.report = report
        self.snapshot_dir = snapshot_dir
        self.snapshots: list[str] = []
        self.truth: frozenset[tuple[str, str, str]] = frozenset()
        """What the world makes true at the end (:attr:`RunResult.truth`)."""
        self.loop = EventLoop(seed=seed)
        self.facts = FactDatabase()
        robot = scenario.robot
        world.add_robot(robot, scenario.model, scenario.robot_at)
        self.sim = Simulation(world, self.loop, robot)
        self.stack = StackSession(scenario.shared_plan, robot) if scenario.shared_plan else None
        self.executors = (self.stack.executors_class if self.stack else RobotExecutors)(
            self.sim, self.say, self.learned,
            lambda who, kind, text: report(self.loop.now(), who, kind, text))
        registry = ExecutorRegistry({name: self.executors for name in library.atomic})
        hatp = HatpPlanner(domain, budget_ms=300)
        self.narrator = Narrator(report, robot, {p.name for p in scenario.people},
                                 last_plan=lambda: hatp.last.plan if hatp.last else None)
        told = Told(log, lambda t, kind, task, agent, data:
                    self.narrator.event(t, kind, agent, data))
        if console is not None:
            told.listeners.append(console.observe)
        self.sup = Supervisor(library, self.facts, robot=robot, loop=self.loop,
                              executors=registry, log=told, planners={"living-room": hatp})
        self.console = console
        if console is not None:
            console.attach(self.sup)
        self.facts.log_changes(self.sup.record)
        self.people, self.perception = furnish(
            world, self.sim, scenario, self.stack, self.facts, self.executors, self.sup,
            self.say)
        for person in self.people.values():
            self.sup.act_listeners.append(person.on_act)
        self.sup.act_listeners.append(self._act_started)
        self.chronicles = ChronicleRecognizer(self.sup) if library.chronicles else None
        self.sessions = Sessions(self.sup)
        self.action_models = (load_action_models(scenario.action_models, self.facts,
                                                 atomic=library.atomic)
                              if scenario.action_models else None)

    # -- during the run ------------------------------------------------------------

    def say(self, who: str, text: str, request: str | None = None) -> None:
        """``who`` says ``text`` (``request``: the robot's ``speak`` request saying it, which
        ends when the sentence has been said)."""
        extra = {"request": request} if request is not None else {}
        self.sup.record("speech", agent=who, text=text, **extra)
        self.report(self.loop.now(), who, "speech", text)

    def learned(self, s: str, p: str, o: Any) -> None:
        """An executor found something out by trying (the bottle is out of reach)."""
        self.facts.set(s, p, o)

    def _act_started(self, run: Any, state: Any, agent: str) -> None:
        self.report(self.loop.now(), agent, "act", f"[{state.act}] {run.type.name}")
        self.snapshot(f"{state.act.lower()}-{run.type.name}",
                      f"{state.act} {run.type.name}"
                      + (f" ({', '.join(str(v) for k, v in run.env.items() if k != 'robot')})"
                         if len(run.env) > 1 else "")
                      + (f" by {agent}" if agent != self.scenario.robot else ""))

    def snapshot(self, label: str, act: str = "") -> None:
        """A picture framing the robot and the people, captioned with the time, the act
        just entered and who looks where (as the robot believes)."""
        if self.snapshot_dir is None:
            return
        name = f"snapshot-{len(self.snapshots) + 1:02d}-{self.loop.now():06.1f}s-{label}.png"
        robot = self.scenario.robot
        x, y, _ = self.world.base_pose(robot)
        points = [(x, y, 0.6), *(h.eyes for h in self.sim.people.values())]
        width, height = SNAPSHOT_SIZE
        caption = [f"{self.loop.now():.1f} s   {act or label}", self._gazes()]
        self.world.snapshot(self.snapshot_dir / name, width, height,
                            framing(points, width / height), caption)
        self.snapshots.append(name)
        self.sup.record("snapshot", file=name)

    def _gazes(self) -> str:
        """Who looks where, as the robot believes: an agent first if one is looked at."""
        agents = [self.scenario.robot, *self.people]
        told = []
        for who in agents:
            seen = sorted(map(str, self.facts.objects(who, "looksAt")),
                          key=lambda target: (target not in agents, target))
            told.append(f"{who} looks at {seen[0]}" if seen else f"{who}: attention unknown")
        return "   ".join(told)

    def go(self) -> float:
        """Run until nothing is left to happen; return the simulated time at the end."""
        for goal in self.scenario.goals:
            self.loop.call_later(goal.at, self._add_goal, goal)
        for person in self.people.values():
            person.begin()
        self.perception.start()
        self.sessions.start()  # the interaction is going on with whoever attends already
        if self.action_models is not None:  # what is there at the start was not done by anyone
            self.sup.recognize(self.action_models)
        if self.stack is not None:
            self.stack.start(self.sup, self.people[self.stack.partner_name],
                             self.scenario.shared_plan["decision-wait"])
        start = time.perf_counter()
        while self.loop.now() < self.scenario.timeout - 1e-9:
            self.loop.advance(min(CHUNK, self.scenario.timeout - self.loop.now()))
            if self.console is not None:  # pause, step, speed and the operator's commands
                self.console.between(self.loop.now())
            if self.world.gui:  # someone is watching: no faster than real time
                time.sleep(max(0.0, self.loop.now() - (time.perf_counter() - start)))
            if self._quiet():
                break
        self.snapshot("end")
        self.sup.record("run-end", scenario=self.scenario.name)
        self.truth = frozenset(self.perception.truth())
        return self.loop.now()

    def _add_goal(self, goal: Any) -> None:
        self.sup.agenda.add(goal.task, goal.args, priority=goal.priority)

    def _quiet(self) -> bool:
        if (self.sup.runs or self.sup.agenda.active is not None
                or any(g.state not in OVER for g in self.sup.agenda.goals)
                or self.sim.busy or any(p.pending for p in self.people.values())):
            return False
        if self.stack is not None:
            if self.stack.busy:
                return False
            self.stack.settle()
        return self.loop.clock.next_due() is None

    # -- after the run --------------------------------------------------------------

    def happened(self, end: float, log_path: Path | None) -> Happened:
        if log_path is not None:
            self.log.flush()
            events = [(e.time, e.kind, e.task, e.agent, e.data) for e in read_events(log_path)]
        else:
            events = self.log.events
        return happened(events, self.facts, self.scenario.robot, end)


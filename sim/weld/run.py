"""Running a seam-welding scenario: the site, the team, the script, the judge, the files.

:func:`run_weld` builds the :class:`~sim.weld.site.WeldSite` as the scenario
says (panels mounted, seams welded), puts each team member where the team
file's ``at`` says (a robot with a ``welding-tool`` is the humanoid, any other
the rover; a person who is not ``remote`` is an avatar), and builds the
:class:`shary.team.Team` on one event loop and one context log, with:

- the site's executors as every robot's world (:mod:`sim.weld.executors`);
- the astronauts' ``mount-panel`` work carried out in the world (they carry
  the panel and tack it; their proxy reports it done);
- the spatial reasoning agent's ``spatial`` service on the perceived poses
  (:meth:`shary.team.spatial.SpatialReasoner.service`), which K-10's
  ``point-light`` queries through the message port;
- a picture from K-10's camera attached to every ``seam-okay`` question;
- the scenario's script (take control, teleoperate, hand back).

It runs until the goal is over and nothing moves, or the timeout, judges the
log against ``expect``, and writes to the output folder: ``log.sqlite``,
``timeline.svg`` (a lane per agent), ``summary.json`` and the camera's PNGs.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Any

from shary.executors import ExecutorRegistry, Reporter, Request
from shary.facts import FactDatabase
from shary.log import ContextLog, read_events
from shary.loop import EventLoop
from shary.team import Team
from shary.team.agents import INFORM, QUERY
from shary.team.proxy import HumanProxy
from shary.team.spatial import SpatialReasoner
from shary.transport.messages import Act, Answer, Assignment, Message, Question
from userfiles.outputs import output_folder, write_output

from ..narration import Report
from ..run import CHUNK, RunResult
from ..simulation import Simulation
from .executors import SiteActions
from .perception import SitePerception
from .scenario import WeldScenario, judge, load_weld_scenario
from .site import WeldSite
from .story import TeamStory

ATOMIC = ("drive", "weld", "inspect", "aim", "point-light", "snapshot")
"""The atomic tasks the site performs for its robots (sim/scenarios/weld/recipes.yaml)."""
HUMANOID_RESOURCE = "welding-tool"
ASK_SPEAKER_FOR = 30.0
"""Seconds K-10 waits for a speaker to say which object or corner they meant."""
SEAM_QUESTION = "seam-okay"
VIEWED = ("question", "answer", "respawn", "associate", "release", "control", "spatial")
"""The events after which ``--snapshots`` takes a view of the whole site."""
SUITS = ((0.95, 0.95, 0.93, 1.0), (0.93, 0.55, 0.2, 1.0), (0.3, 0.55, 0.9, 1.0))
"""Suit colours, one per astronaut in turn (white, orange, blue)."""


def run_weld(path: str | Path, *, seed: int = 0, out: str | Path | None = None,
             snapshots: bool = False, gui: bool = False,
             report: Report | None = None, console: Any = None) -> RunResult:
    """Run one seam-welding scenario (see the module's docstring).  Pictures from K-10's
    camera are written whenever there is an output folder (they go with its questions);
    ``snapshots`` adds a view of the whole site at the end.  ``console`` (a
    :class:`shary.console.live.Attachment`) is given the team, sees every logged event and
    is called between two steps of the clock, as in :func:`sim.run.run_scenario`."""
    scenario = load_weld_scenario(path)
    out_dir = Path(out) if out is not None else None
    log_path = None
    if out_dir is not None:
        output_folder(out_dir)
        for stale in [*out_dir.glob("*.png"), out_dir / "log.sqlite"]:
            stale.unlink(missing_ok=True)
        log_path = out_dir / "log.sqlite"
    wall = time.perf_counter()
    story = TeamStory(report or (lambda t, who, kind, text: None))
    with WeldSite(gui=gui) as site:
        log: Any = ContextLog(log_path, seed=seed) if log_path is not None else _Rows()
        try:
            run = _WeldRun(scenario, site, _Told(log, story, console), seed, out_dir,
                           views=snapshots)
            setup = time.perf_counter() - wall
            wall = time.perf_counter()
            end = run.go()
            wall = time.perf_counter() - wall
            if log_path is not None:
                log.flush()
                rows = [(e.time, e.kind, e.task, e.agent, e.data) for e in read_events(log_path)]
            else:
                rows = log.rows
            differences = judge(scenario.expect, rows, run.team.tasks.outcome, end)
            if end >= scenario.timeout - 1e-9:
                differences.append(f"the run was still going at the timeout "
                                   f"({scenario.timeout:g}s)")
            result = RunResult(scenario.name, not differences, differences, end, wall, setup,
                               seed, run.sim.physics_steps + site_steps(site))
            if out_dir is not None:
                if snapshots:
                    run.overview("end")
                result.outputs = run.write(out_dir, log)
                write_output(out_dir / "summary.json", json.dumps(result.summary(), indent=2)
                             + "\n")
                result.outputs["summary"] = str(out_dir / "summary.json")
        finally:
            if hasattr(log, "close"):
                log.close()
    return result


def site_steps(site: WeldSite) -> int:
    """Physics steps the site took (carried panels), from its clock."""
    return round(site.time / site.timestep)


class _Rows:
    """The context log's interface, kept in memory when no output folder is asked for."""

    def __init__(self) -> None:
        self.rows: list[tuple[float, str, str | None, str | None, dict[str, Any]]] = []

    def record(self, t: float, kind: str, *, task: str | None = None,
               agent: str | None = None, **data: Any) -> int:
        self.rows.append((t, kind, task, agent, data))
        return len(self.rows)

    def flush(self) -> None:
        pass


class _Told:
    """The context log, each event also told to the story (and to ``watchers``)."""

    def __init__(self, log: Any, story: TeamStory, console: Any = None):
        self.log = log
        self.story = story
        self.console = console
        self.watchers: list[Any] = []
        if hasattr(log, "path"):
            self.path = log.path  # the Context Manager reads the log's file

    def record(self, t: float, kind: str, *, task: str | None = None,
               agent: str | None = None, **data: Any) -> int:
        row = self.log.record(t, kind, task=task, agent=agent, **data)
        self.story.event(t, kind, agent, data, task)
        if self.console is not None:
            self.console.observe(t, kind, task, agent, data)
        for watcher in self.watchers:
            watcher(kind, agent, task)
        return row

    def flush(self) -> None:
        self.log.flush()


class _WeldRun:
    """One run's parts, wired together."""

    def __init__(self, scenario: WeldScenario, site: WeldSite, log: _Told, seed: int,
                 out_dir: Path | None, views: bool = False):
        self.scenario = scenario
        self.site = site
        self.out_dir = out_dir
        self.views = 0
        if views and out_dir is not None:
            log.watchers.append(self._moment)
        spec = scenario.team
        self.loop = EventLoop(seed=seed)
        self.facts = FactDatabase()
        for panel in scenario.mounted:
            site.mount(panel)
        for seam, quality in scenario.welded.items():
            site.lay_bead(seam, quality)
        for robot in spec.of_kind("robot"):
            model = "pr2like" if HUMANOID_RESOURCE in robot.resources else "k10"
            x, y = robot.at[:2] if robot.at else (0.0, -3.0)
            site.add_robot(robot.name, model, (x, y, math.pi / 2))
        self.sim = Simulation(site, self.loop, next(iter(site.robots), ""))
        self.actions = SiteActions(site, self.sim, qualities=scenario.welds,
                                   snapshot_dir=out_dir, tell=self._told)
        for i, person in enumerate(p for p in spec.of_kind("human") if not p.remote):
            x, y = person.at[:2] if person.at else (5.0 + i, -3.4)
            self.actions.add_person(person.name, x, y, math.pi / 2, SUITS[i % len(SUITS)])
        self.world = {robot.name: ExecutorRegistry({a: _Verdicts(self.actions, self.facts)
                                                    for a in ATOMIC})
                      for robot in spec.of_kind("robot")}
        self.log = log
        self.team = Team(spec, loop=self.loop, log=log, facts=self.facts,
                         executors=self.world)
        self._spatial()
        for name in self.world:
            self.team.robot(name).world.register(
                "point-light", _Light(self.team, self.actions, name))
        self.team.attach(SEAM_QUESTION, self._seam_picture)
        for agent in self.team.agents.values():
            if isinstance(agent, HumanProxy) and agent.name in self.actions.people:
                agent.performers["mount-panel"] = self._mounter(agent)
        self.perception = SitePerception(site, self.actions.people, self.facts,
                                         self.team.agents)
        self.perception.a_priori()
        self.perception.update()
        self.sim.observers.append(self.perception.update)
        for step in scenario.script:
            self.loop.call_later(step.at, self._scripted, step)

    # -- wiring ---------------------------------------------------------------------

    def _spatial(self) -> None:
        """The software agent that offers ``spatial`` answers on the perceived poses."""
        reasoner = SpatialReasoner(self.facts)
        for agent in self.team.agents.values():
            if "spatial" in agent.spec.services and hasattr(agent, "offer"):
                agent.offer("spatial", reasoner.service)

    def _mounter(self, proxy: HumanProxy) -> Any:
        def perform(message: Assignment) -> None:
            panel = str(message.args.get("panel", ""))
            carriers = [proxy.name, *[h for h in [message.args.get("helper")] if h]]
            def over() -> None:
                if self.site.mounted(panel):
                    proxy.report(message.task, "done")
                else:  # physics had the last word: something stood in the way
                    proxy.report(message.task, "failed", f"{panel} did not reach its place "
                                 "on the frame")

            try:
                self.actions.mount(panel, carriers, over)
            except KeyError as err:
                proxy.report(message.task, "failed", str(err.args[0]))
        return perform

    def _seam_picture(self, robot: Any, request: Request) -> dict[str, Any]:
        """What a seam-okay question carries: a picture of the seam from the robot's camera
        (its head still aimed at it), and which seam."""
        task = self.scenario.team.tasks.get(robot.current or "")
        seam = str(task.args.get("seam")) if task is not None else None
        image = self.actions.snapshot(robot.name, f"question-{seam or 'seam'}",
                                      f"{robot.name}: is this seam okay? ({seam})")
        return {k: v for k, v in (("image", image), ("seam", seam)) if v}

    def _told(self, who: str, kind: str, text: str) -> None:
        self.team.record("site", agent=who, what=kind, text=text)

    def _scripted(self, step: Any) -> None:
        if step.action == "take-control":
            self.team.take_control(step.by, step.robot)
        elif step.action == "hand-back":
            self.team.hand_back(step.by, step.robot)
        else:
            self.team.robot(step.robot).teleoperate(step.by, step.atomic, step.args)

    # -- running ----------------------------------------------------------------------

    def go(self) -> float:
        """Run until the goal is over and nothing moves; the simulated time at the end."""
        from shary.console.teamlive import roster

        console = self.log.console
        self.team.record("team", **roster(self.team))
        for member in self.scenario.team.agents.values():
            if member.kind != "software":  # each a lane of the timeline, in the file's order
                self.team.record("member", agent=member.name, member_kind=member.kind,
                                 skills=list(member.skills), remote=member.remote or None)
        if console is not None:
            console.attach(self.team)
        self.team.start()
        timeout = self.scenario.timeout
        while self.loop.now() < timeout - 1e-9:
            self.loop.advance(min(CHUNK, timeout - self.loop.now()))
            if self.site.gui:
                time.sleep(CHUNK)
            if console is not None:  # pause, step, speed and the operator's commands
                console.between(self.loop.now())
            if self.team.tasks.outcome is not None and not self.sim.busy \
                    and self.loop.clock.next_due() is None:
                break
        self.team.record("run-end", scenario=self.scenario.name)
        return self.loop.now()

    def _moment(self, kind: str, agent: str | None, task: str | None) -> None:
        """A view of the whole site at the moments worth seeing (``--snapshots``)."""
        if kind in VIEWED:
            self.overview(f"{kind}" + (f" by {agent}" if agent else ""))

    def overview(self, label: str) -> None:
        """A view of the whole site, framing every robot and astronaut and the frame."""
        from ..world import framing

        assert self.out_dir is not None
        self.views += 1
        now = self.loop.now()
        path = self.out_dir / f"site-{self.views:02d}-{now:06.1f}s-{label.replace(' ', '-')}.png"

        points = [(x, y, 0.6) for x, y, _ in (self.site.base_pose(r) for r in self.site.robots)]
        points += [(a.x, a.y, 1.0) for a in self.actions.people.values()]
        points += [(0.0, 0.0, 1.0), (4.0, 0.0, 1.0)]
        self.site.snapshot(path, 800, 600, framing(points, 4 / 3),
                           [f"{now:.1f} s   {self.scenario.name}: {label}"])

    def write(self, out_dir: Path, log: Any) -> dict[str, str]:
        from shary.timeline import write_timeline

        outputs = {"log": str(out_dir / "log.sqlite")}
        log.flush()
        write_timeline(out_dir / "log.sqlite", out_dir / "timeline.svg",
                       title=self.scenario.name)
        outputs["timeline"] = str(out_dir / "timeline.svg")
        pictures = sorted(str(p) for p in out_dir.glob("*.png"))
        if pictures:
            outputs["snapshots"] = ", ".join(pictures)
        return outputs


class _Verdicts:
    """The site's executors, with what an inspection read kept as a fact (``SEAM verdict
    sound|unsure``), which the recipes choose by (ask a person when unsure)."""

    def __init__(self, actions: SiteActions, facts: FactDatabase):
        self.actions = actions
        self.facts = facts

    def start(self, request: Request, reporter: Reporter) -> None:
        if request.atomic != "inspect":
            self.actions.start(request, reporter)
            return
        self.actions.start(request, _Noting(reporter, self.facts))

    def cancel(self, request: Request) -> None:
        self.actions.cancel(request)


class _Noting:
    """A reporter that notes an inspection's verdict as a fact before passing it on."""

    def __init__(self, reporter: Reporter, facts: FactDatabase):
        self.reporter = reporter
        self.facts = facts

    def done(self, request: Request, **result: Any) -> None:
        self.facts.set(request.args["seam"], "verdict", str(result.get("verdict")))
        self.reporter.done(request, **result)

    def failed(self, request: Request, reason: str) -> None:
        self.facts.remove(request.args["seam"], "verdict", "unsure")
        self.reporter.failed(request, reason)

    def cancelled(self, request: Request, reason: str = "cancelled") -> None:
        self.reporter.cancelled(request, reason)


class _Light:
    """K-10's ``point-light``: the words go to the spatial reasoning agent (a ``QUERY``
    through the message port); its point is where the head turns.  An ambiguous reference
    comes back as a question, which K-10 puts to the speaker (a multiple-choice
    ``Question`` message, answered through the person's proxy): a chosen corner is
    lit, a chosen object is resolved again; no answer within :data:`ASK_SPEAKER_FOR`
    seconds, or a question without choices, fails the step with the question."""

    def __init__(self, team: Team, actions: SiteActions, robot: str):
        self.team = team
        self.actions = actions
        self.robot = robot
        self.address = f"{robot}/spatial"
        self.waiting: dict[str, tuple[Request, Reporter]] = {}
        """Query or question id -> the step waiting for it."""
        self.meanings: dict[str, dict[str, Any]] = {}
        """Question id -> what each of its choices means (a point, an object's name)."""
        self.timers: dict[str, Any] = {}
        team.port.subscribe(self.address, self._heard)

    def start(self, request: Request, reporter: Reporter, referent: str | None = None) -> None:
        reasoner = next((a.name for a in self.team.agents.values()
                         if "spatial" in a.spec.services), None)
        if reasoner is None:
            reporter.failed(request, "no agent of the team offers spatial reasoning")
            return
        qid = self.team.port.new_id("s")
        self.waiting[qid] = (request, reporter)
        self.team.port.send(Act(self.address, reasoner, id=qid, act=QUERY, data={
            "service": "spatial", "words": request.args.get("words", ""),
            "speaker": request.args.get("speaker", ""), "addressee": self.robot,
            **({"referent": referent} if referent else {})}))

    def _heard(self, message: Message) -> None:
        found = self.waiting.pop(message.id if isinstance(message, Act)
                                 else getattr(message, "question", ""), None)
        if found is None:
            return
        request, reporter = found
        if isinstance(message, Answer):
            self._answered(message, request, reporter)
        elif isinstance(message, Act) and message.act == INFORM:
            self._informed(message.data, request, reporter)

    def _informed(self, data: dict[str, Any], request: Request, reporter: Reporter) -> None:
        self.team.record("spatial", agent=self.robot, **{k: v for k, v in data.items()
                                                        if k not in ("service", "answers")})
        point = data.get("point")
        if point:
            self._aim(point, request, reporter)
            return
        speaker = str(data.get("to") or request.args.get("speaker", ""))
        choices = tuple(data.get("choices") or ())
        if not choices or speaker not in self.team.agents:
            reporter.failed(request, f"ambiguous: {data.get('question') or data.get('error')}")
            return
        qid = self.team.port.new_id("q")
        self.waiting[qid] = (request, reporter)
        self.meanings[qid] = dict(data.get("answers") or {})
        self.team.record("question", task=request.node, agent=self.robot, question=qid,
                         text=data.get("question"), question_type="multiple-choice",
                         choices=list(choices), to=speaker, expires=ASK_SPEAKER_FOR)
        self.team.port.send(Question(self.address, speaker, id=qid,
                                     text=str(data.get("question")), type="multiple-choice",
                                     choices=choices, expires=ASK_SPEAKER_FOR,
                                     topic="spatial", task=request.node))
        self.timers[qid] = self.team.loop.call_later(ASK_SPEAKER_FOR, self._unanswered, qid)

    def _answered(self, answer: Answer, request: Request, reporter: Reporter) -> None:
        meaning = self.meanings.pop(answer.question, {}).get(str(answer.value))
        timer = self.timers.pop(answer.question, None)
        if timer is not None:
            timer.cancel()
        self.team.record("answer", task=request.node, agent=answer.sender,
                         question=answer.question, asker=self.robot, value=answer.value)
        if isinstance(meaning, list):
            self._aim(meaning, request, reporter)
        elif isinstance(meaning, str):
            self.start(request, reporter, referent=meaning)
        else:
            reporter.failed(request, f"{answer.sender} answered {answer.value!r}, not one of "
                                     "the choices")

    def _unanswered(self, qid: str) -> None:
        self.timers.pop(qid, None)
        found = self.waiting.pop(qid, None)
        self.meanings.pop(qid, None)
        if found is not None:
            request, reporter = found
            reporter.failed(request, f"nobody said which within {ASK_SPEAKER_FOR:g}s")

    def _aim(self, point: list[float], request: Request, reporter: Reporter) -> None:
        x, y, z = (float(v) for v in point)
        aim = Request(request.id, "point-light", {"x": x, "y": y, "z": z}, request.agent,
                      request.node)
        self.actions.start(aim, reporter)

    def cancel(self, request: Request) -> None:
        for qid, (waiting, _) in list(self.waiting.items()):
            if waiting.id == request.id:
                del self.waiting[qid]
                self.meanings.pop(qid, None)
        self.actions.cancel(request)

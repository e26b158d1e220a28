"""Running a seam-welding scenario in one process: the world, the team, the judge, the files.

:func:`run_weld` builds, on one event loop and one context log, the scenario's
world agent (:class:`~sim.weld.world.WeldWorld`: the site with every robot and
on-site person where the team file's ``at`` says, its executors, perception
and avatars) and the :class:`shary.team.Team`, and connects them through the
team's message port as they would be connected across processes
(:func:`shary.team.world.connect_world`): the robots' atomic tasks, the
astronauts' ``mount-panel`` and the pictures K-10's questions carry are
messages to the world.  Beside them:

- the spatial reasoning agent's ``spatial`` service on the perceived poses
  (:meth:`shary.team.spatial.SpatialReasoner.service`), which K-10's
  ``point-light`` queries through the message port (:func:`offer_spatial`);
- the scenario's script (take control, teleoperate, hand back:
  :func:`schedule_script`);
- a member killed at a given time (``kill``, drawn by a behaviour campaign,
  :mod:`sim.fuzz.behaviours`): it falls silent and the managers react as to a
  lost process (:meth:`shary.team.Team.kill`); a robot's motion in the world
  stops with it.

It runs until the goal is over and nothing moves, or the timeout, judges the
log against ``expect``, and writes to the output folder: ``log.sqlite``,
``timeline.svg`` (a lane per agent), ``summary.json`` and the camera's PNGs.
``shary team up`` runs the same parts each in its own process
(:mod:`sim.weld.agent`).
"""

from __future__ import annotations

import json
import time
from collections.abc import Collection
from pathlib import Path
from typing import Any

from shary.facts.database import FactDatabase
from shary.kernel.loop import EventLoop
from shary.log.contextlog import ContextLog, read_events
from shary.log.told import Told
from shary.team import Team
from shary.team.spatial import SpatialReasoner
from shary.team.world import connect_world
from userfiles.outputs import output_folder, write_output

from ..narration import Report
from ..results import CHUNK, MemoryLog, RunResult
from .scenario import WeldScenario, judge, load_weld_scenario
from .site import WeldSite
from .story import TeamStory
from .world import WeldWorld

VIEWED = ("question", "answer", "respawn", "associate", "release", "control", "spatial")
"""The events after which ``--snapshots`` takes a view of the whole site."""


def run_weld(path: str | Path | WeldScenario, *, seed: int = 0, out: str | Path | None = None,
             snapshots: bool = False, gui: bool = False,
             report: Report | None = None, console: Any = None,
             kill: tuple[str, float] | None = None) -> RunResult:
    """Run one seam-welding scenario (see the module's docstring).  Pictures from K-10's
    camera are written whenever there is an output folder (they go with its questions);
    ``snapshots`` adds a view of the whole site at the end.  ``console`` (a
    :class:`shary.console.live.Attachment`) is given the team, sees every logged event and
    is called between two steps of the clock, as in :func:`sim.run.run_scenario`.
    ``path`` may be a scenario already loaded; ``kill`` (member, seconds) kills that
    member's process then, in this process (see the module's docstring)."""
    scenario = path if isinstance(path, WeldScenario) else load_weld_scenario(path)
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
        log: Any = ContextLog(log_path, seed=seed) if log_path is not None else MemoryLog()
        told = Told(log, lambda t, kind, task, agent, data:
                    story.event(t, kind, agent, data, task))
        if console is not None:
            told.listeners.append(console.observe)
        try:
            run = _WeldRun(scenario, site, told, seed, out_dir, views=snapshots,
                           console=console, kill=kill)
            setup = time.perf_counter() - wall
            wall = time.perf_counter()
            end = run.go()
            wall = time.perf_counter() - wall
            if log_path is not None:
                log.flush()
                rows = [(e.time, e.kind, e.task, e.agent, e.data) for e in read_events(log_path)]
            else:
                rows = log.events
            differences = judge(scenario.expect, rows, run.team.tasks.outcome, end)
            if end >= scenario.timeout - 1e-9:
                differences.append(f"the run was still going at the timeout "
                                   f"({scenario.timeout:g}s)")
            result = RunResult(scenario.name, not differences, differences, end, wall, setup,
                               seed, run.sim.physics_steps + site_steps(site),
                               events=rows if log_path is None else [],
                               truth=site_truth(site))
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


def offer_spatial(team: Team) -> None:
    """The software agent that offers ``spatial`` answers, on the team's perceived poses."""
    reasoner = SpatialReasoner(team.facts)
    for agent in team.agents.values():
        if "spatial" in agent.spec.services and hasattr(agent, "offer"):
            agent.offer("spatial", reasoner.service)


def record_members(team: Team, elsewhere: Collection[str] = ()) -> None:
    """The team's roster (``team``: what the console shows of it; ``elsewhere``: the
    members in processes of their own), and a ``member`` row per agent that acts: each a
    lane of the timeline, in the file's order."""
    from shary.console.teamlive import roster

    team.record("team", **roster(team, elsewhere))
    for member in team.spec.agents.values():
        if member.kind != "software":
            team.record("member", agent=member.name, member_kind=member.kind,
                        skills=list(member.skills), remote=member.remote or None)


def schedule_script(team: Team, scenario: WeldScenario) -> None:
    """What people do at given times beyond their behaviour (take control, teleoperate,
    hand back), as their messages to the robot, on the team's clock."""
    def scripted(step: Any) -> None:
        if step.action == "take-control":
            team.take_control(step.by, step.robot)
        elif step.action == "hand-back":
            team.hand_back(step.by, step.robot)
        else:
            team.teleoperate(step.by, step.robot, step.atomic, step.args)

    for step in scenario.script:
        team.loop.call_later(step.at, scripted, step)


def site_truth(site: WeldSite) -> frozenset[tuple[str, str, str]]:
    """What the site makes true now: the panels ``mounted`` on the frame, the seams
    ``welded`` and the ``quality`` of each bead (:attr:`sim.results.RunResult.truth`)."""
    return frozenset({*((panel, "mounted", "true") for panel in site.panels
                        if site.mounted(panel)),
                      *((seam, "welded", "true") for seam in site.beads),
                      *((seam, "quality", f"{bead.quality:g}")
                        for seam, bead in site.beads.items())})


def site_steps(site: WeldSite) -> int:
    """Physics steps the site took (carried panels), from its clock."""
    return round(site.time / site.timestep)


class _WeldRun:
    """One run's parts, wired together: the world agent and the team on one loop."""

    def __init__(self, scenario: WeldScenario, site: WeldSite, log: Told, seed: int,
                 out_dir: Path | None, views: bool = False, console: Any = None,
                 kill: tuple[str, float] | None = None):
        self.scenario = scenario
        self.site = site
        self.out_dir = out_dir
        self.views = 0
        self.console = console
        if views and out_dir is not None:
            log.listeners.append(self._moment)
        self.loop = EventLoop(seed=seed)
        self.facts = FactDatabase()
        self.log = log
        self.team = Team(scenario.team, loop=self.loop, log=log, facts=self.facts)
        self.world = WeldWorld(scenario, site, self.team.port, self.facts, self.team.record,
                               out_dir)
        self.sim = self.world.sim
        self.actions = self.world.actions
        self.links = connect_world(self.team)
        offer_spatial(self.team)
        schedule_script(self.team, scenario)
        if kill is not None:  # a process that outlives the goal is no longer killed
            timer = self.loop.call_later(kill[1], self._kill, kill[0])
            self.team.tasks.listeners.append(lambda outcome: timer.cancel())

    def _kill(self, name: str) -> None:
        """``name``'s process dies: what it asked the world stops, what it carried is put
        down, then it falls silent."""
        self.world.left(name)
        link = self.links.get(name)
        if link is not None:
            link.cut()
        self.team.kill(name)

    # -- running ----------------------------------------------------------------------

    def go(self) -> float:
        """Run until the goal is over and nothing moves; the simulated time at the end."""
        console = self.console
        record_members(self.team)
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

    def _moment(self, t: float, kind: str, task: str | None, agent: str | None,
                data: dict[str, Any]) -> None:
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
        from shary.log.timeline import write_timeline

        outputs = {"log": str(out_dir / "log.sqlite")}
        log.flush()
        write_timeline(out_dir / "log.sqlite", out_dir / "timeline.svg",
                       title=self.scenario.name)
        outputs["timeline"] = str(out_dir / "timeline.svg")
        pictures = sorted(str(p) for p in out_dir.glob("*.png"))
        if pictures:
            outputs["snapshots"] = ", ".join(pictures)
        return outputs

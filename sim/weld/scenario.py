"""Seam-welding scenario files: a team on the site, a script, and the expected outcome.

A weld scenario (``sim/scenarios/weld-*.yaml``) is a scenario whose ``site``
is ``seam-welding``.  It names a team file (:mod:`shary.team.teamfile`: the
agents, their behaviours, the questions and the goal), says which panels are
mounted and which seams welded at the start, the quality of each weld the
torch lays, what people do at given times beyond their behaviour (take
control of a robot, teleoperate it, hand it back), and what must happen.  It
is loaded safely, checked against ``sim/schemas/weld-scenario.schema.json``
and for meaning (the team file's own problems included, with its lines;
every agent, task and atomic task named must exist), and every problem is
reported as ``FILE:LINE:COL: error: …``.

:func:`judge` compares a run's context log with ``expect`` and lists every
difference in words.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from shary.team import TeamSpec, load_team, robot_library
from userfiles.errors import FileError
from userfiles.reader import Reader, read, spelled
from userfiles.schema import did_you_mean

from ..schemafiles import schema
from .layout import PANELS, seam_panels

SITE = "seam-welding"
DEFAULT_TIMEOUT = 300.0


@dataclass(frozen=True)
class Scripted:
    """One thing a person does at a time: ``take-control``, ``teleoperate``, ``hand-back``."""

    at: float
    by: str
    action: str
    robot: str
    atomic: str = ""
    args: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class WeldExpect:
    goal: str | None = None
    tasks: dict[str, str] = field(default_factory=dict)
    done_by: dict[str, str] = field(default_factory=dict)
    order: tuple[tuple[str, str], ...] = ()
    parallel: tuple[tuple[str, str], ...] = ()
    events: tuple[str, ...] = ()
    no_events: tuple[str, ...] = ()
    images: int = 0
    within: float | None = None


@dataclass(frozen=True)
class WeldScenario:
    """A checked seam-welding scenario (see the module's docstring)."""

    name: str
    file: Path
    doc: str
    team: TeamSpec
    mounted: tuple[str, ...]
    welded: dict[str, float]
    welds: dict[str, list[float]]
    script: tuple[Scripted, ...]
    timeout: float
    expect: WeldExpect


def is_weld_scenario(data: Any) -> bool:
    """Whether a loaded YAML document is a seam-welding scenario (its ``site``)."""
    return isinstance(data, dict) and data.get("site") == SITE


def load_weld_scenario(path: str | Path, *, text: str | None = None,
                       team_text: str | None = None) -> WeldScenario:
    """Load and check a weld scenario and its team file; raise :class:`FileError` listing
    every problem of both.  ``text`` and ``team_text`` are read in place of the
    scenario's and its team file's own texts, as if they were those files (``shary
    fuzz`` varies a built-in scenario and its team in memory this way)."""
    return read(path, schema("weld-scenario"), lambda reader: _meaning(reader, team_text),
                text=text)


def _meaning(reader: Reader, team_text: str | None = None) -> WeldScenario:
    data = reader.data
    problem = reader.problem
    team: TeamSpec | None = None
    full = reader.confined_path(("team",), data["team"])
    if full is not None:
        try:
            team = load_team(spelled(full, like=reader.file), text=team_text)
        except FileError as err:
            reader.problems.extend(err.problems)
            problem(("team",), f"the team file {data['team']} has errors")
    mounted = tuple(data.get("mounted") or ())
    welded = dict(data.get("welded") or {})
    for seam in welded:
        for panel in seam_panels(seam):
            if panel not in mounted:
                problem(("welded", seam), f"{seam} cannot be welded at the start: {panel} is "
                        "not mounted (add it to 'mounted:')", key=True)
    welds = {seam: list(q) for seam, q in (data.get("welds") or {}).items()}
    script = tuple(_scripted(reader, i, raw, team) for i, raw in enumerate(data.get("script")
                                                                            or []))
    timeout = reader.duration(("timeout",), data.get("timeout", DEFAULT_TIMEOUT))
    expect = _expect(reader, data.get("expect") or {}, team)
    for i, step in enumerate(script):
        if step.at >= timeout > 0:
            problem(("script", i, "at"), f"at {step.at:g}s comes after the run's timeout "
                    f"({timeout:g}s): it would never happen")
    if team is not None and team.tasks:
        for name, task in team.tasks.items():
            panel = task.args.get("panel")
            if panel is not None and panel not in PANELS:
                problem(("team",), f"the team's task {name} names panel {panel!r}, which the "
                        f"site does not have (panels: {', '.join(PANELS)})")
    return WeldScenario(data["scenario"], Path(reader.file), data.get("doc", ""),
                        team if team is not None else TeamSpec("", {}, {}, {}),
                        mounted, welded, welds, script, timeout, expect)


def _scripted(reader: Reader, i: int, raw: dict[str, Any], team: TeamSpec | None) -> Scripted:
    where = ("script", i)
    at = reader.duration((*where, "at"), raw["at"])
    actions = [a for a in ("take-control", "hand-back", "teleoperate") if a in raw]
    if len(actions) != 1:
        reader.problem(where, "a script step does one of take-control, teleoperate or "
                       "hand-back")
        return Scripted(at, raw["by"], "", "")
    action = actions[0]
    robot = raw[action]
    if (action == "teleoperate") != ("do" in raw):
        reader.problem(where, "'do:' (the atomic task) goes with 'teleoperate:' only")
    if "with" in raw and action != "teleoperate":
        reader.problem((*where, "with"), "'with:' goes with 'teleoperate:' only", key=True)
    if team is not None and team.agents:
        humans = [a.name for a in team.of_kind("human")]
        robots = [a.name for a in team.of_kind("robot")]
        if raw["by"] not in humans:
            reader.problem((*where, "by"), f"no person {raw['by']!r} in the team"
                           f"{did_you_mean(raw['by'], humans)} (people: {', '.join(humans)})")
        if robot not in robots:
            reader.problem((*where, action), f"no robot {robot!r} in the team"
                           f"{did_you_mean(robot, robots)} (robots: {', '.join(robots)})")
        atomic = raw.get("do")
        if atomic is not None:
            known = sorted(robot_library(team).atomic)
            if atomic not in known:
                reader.problem((*where, "do"), f"no atomic task {atomic!r}"
                               f"{did_you_mean(atomic, known)} (atomic tasks: "
                               f"{', '.join(known)})")
    return Scripted(at, raw["by"], action, robot, raw.get("do", ""), dict(raw.get("with") or {}))


def _expect(reader: Reader, raw: dict[str, Any], team: TeamSpec | None) -> WeldExpect:
    tasks = set(team.tasks) if team is not None else set()
    agents = set(team.agents) if team is not None else set()

    def known_task(where: tuple, name: str, key: bool = False) -> None:
        if tasks and name not in tasks:
            reader.problem(where, f"no task {name!r} in the team's goal"
                           f"{did_you_mean(name, tasks)}", key=key)

    for name in raw.get("tasks") or {}:
        known_task(("expect", "tasks", name), name, key=True)
    for name, agent in (raw.get("done-by") or {}).items():
        known_task(("expect", "done-by", name), name, key=True)
        if agents and agent not in agents:
            reader.problem(("expect", "done-by", name), f"no agent {agent!r} in the team"
                           f"{did_you_mean(agent, agents)}")
    for group in ("order", "parallel"):
        for i, pair in enumerate(raw.get(group) or []):
            for j, name in enumerate(pair):
                known_task(("expect", group, i, j), name)
    for group in ("events", "no-events"):
        for i, event in enumerate(raw.get(group) or []):
            _, _, who = event.partition(" by ")
            if who and agents and who not in agents:
                reader.problem(("expect", group, i), f"no agent {who!r} in the team"
                               f"{did_you_mean(who, agents)}")
    within = raw.get("within")
    return WeldExpect(
        raw.get("goal"), dict(raw.get("tasks") or {}), dict(raw.get("done-by") or {}),
        tuple(tuple(p) for p in raw.get("order") or ()),  # type: ignore[misc]
        tuple(tuple(p) for p in raw.get("parallel") or ()),  # type: ignore[misc]
        tuple(raw.get("events") or ()), tuple(raw.get("no-events") or ()),
        int(raw.get("images", 0)),
        reader.duration(("expect", "within"), within) if within is not None else None)


# ---------------------------------------------------------------------- judging

Row = tuple[float, str, str | None, str | None, dict[str, Any]]
"""(time, kind, task, agent, data): a context-log row."""


def judge(expect: WeldExpect, rows: list[Row], outcome: str | None, end: float) -> list[str]:
    """Every way the run's log differs from what the scenario expects, in words."""
    differences = []
    if expect.goal is not None and outcome != expect.goal:
        differences.append(f"the goal ended {outcome or 'unfinished'}, expected {expect.goal}")
    started: dict[str, list[float]] = {}
    ended: dict[str, list[float]] = {}
    fates: dict[str, set[str]] = {}
    doers: dict[str, set[str]] = {}
    for t, kind, task, agent, _ in rows:
        if task is None:
            continue
        if kind == "task-running":
            started.setdefault(task, []).append(t)
        elif kind in ("task-done", "task-failed", "task-given-up"):
            ended.setdefault(task, []).append(t)
            fates.setdefault(task, set()).add(kind[len("task-"):])
            if kind == "task-done" and agent:
                doers.setdefault(task, set()).add(agent)
        elif kind == "respawn":
            fates.setdefault(task, set()).add("respawned")
    for task, fate in expect.tasks.items():
        if fate not in fates.get(task, set()):
            seen = ", ".join(sorted(fates.get(task, ()))) or "nothing"
            differences.append(f"task {task}: expected {fate}, saw {seen}")
    for task, agent in expect.done_by.items():
        if agent not in doers.get(task, set()):
            differences.append(f"task {task}: expected done by {agent}, done by "
                               f"{', '.join(sorted(doers.get(task, ()))) or 'nobody'}")
    for first, then in expect.order:
        if first not in ended or then not in started:
            differences.append(f"{first} before {then}: "
                               f"{first if first not in ended else then} never "
                               f"{'ended' if first not in ended else 'started'}")
        elif min(ended[first]) > max(started[then]):
            differences.append(f"{then} started at {max(started[then]):.1f}s, before "
                               f"{first} ended ({min(ended[first]):.1f}s)")
    for a, b in expect.parallel:
        spans = {n: (min(started.get(n, [end])), max(ended.get(n, [end]))) for n in (a, b)}
        if max(spans[a][0], spans[b][0]) >= min(spans[a][1], spans[b][1]):
            differences.append(f"{a} and {b} did not run at the same time "
                               f"({a}: {spans[a][0]:.1f}-{spans[a][1]:.1f}s, "
                               f"{b}: {spans[b][0]:.1f}-{spans[b][1]:.1f}s)")
    i = 0
    for _, kind, _, agent, data in rows:
        if i < len(expect.events) and _matches(expect.events[i], kind, agent, data):
            i += 1
    if i < len(expect.events):
        differences.append(f"expected the events {', '.join(expect.events)} in this order; "
                           f"missing from {expect.events[i]!r} on")
    for event in expect.no_events:
        hits = [t for t, kind, _, agent, data in rows if _matches(event, kind, agent, data)]
        if hits:
            differences.append(f"unexpected {event!r} at {hits[0]:.1f}s")
    images = sum(1 for _, kind, _, _, data in rows
                 if kind == "question" and isinstance(data.get("data"), dict)
                 and (data["data"].get("picture") or data["data"].get("image")))
    if images < expect.images:
        differences.append(f"expected at least {expect.images} question(s) with an image, "
                           f"saw {images}")
    if expect.within is not None and end > expect.within:
        differences.append(f"took {end:.1f}s, expected within {expect.within:g}s")
    return differences


def _matches(event: str, kind: str, agent: str | None, data: dict[str, Any]) -> bool:
    """Whether a row is the event ``KIND [by AGENT]``; a progress status (``refused``,
    ``accepted``, ``served``) names the message that carried it."""
    name, _, who = event.partition(" by ")
    same = kind == name or (kind == "message" and data.get("type") == "progress"
                            and data.get("status") == name)
    return same and (not who or agent == who)

"""A team run live under the console: the operator's team actions, and team files run alone.

The console steers a team through the same :class:`~shary.console.live.LiveRun`
as a single robot (one run thread, pause, step, speed, act breakpoints); what
differs is what an operator may do, which :class:`TeamSteering` holds:

* :meth:`TeamSteering.check`, on the server's thread, checks a message against
  the console's picture of the run (:class:`~shary.console.teamview.TeamView`):
  the question is open and held by that person, and the answer fits its type;
  the robot is a robot, the person a person; a teleoperated atomic task is one
  of the robot's, with exactly its parameters; the team task is running;
* :meth:`TeamSteering.perform`, on the run's thread between two steps of the
  clock, acts through the team's own ports, as a person's interface would:
  ``HumanProxy.answer`` (the Interaction Manager routes the answer), the
  ``TAKE-CONTROL``/``HAND-BACK`` acts (:meth:`~shary.team.Team.take_control`),
  :meth:`~shary.team.robot.RobotAgent.teleoperate` (the robot's executor
  port), and the Task Manager's withdrawal of a cancelled team task (its holder, a
  robot or a person's proxy, is told and stops: the same in one process or many);
* a **breakpoint on a robot** (HRI/OS Section 3.9): the robot finishes the
  atomic task it is doing and stops before its next one (its executors are
  wrapped by :class:`_Stop`); the rest of the team goes on; clearing it starts
  the held atomic task.  Teleoperation in user mode passes.

:func:`run_team` runs a team file alone (people and software agents; robots
need a world, which a seam-welding scenario gives them) on a simulated clock.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from shary.kernel.executors import Executor, Reporter, Request
from shary.team.agents import USER

if TYPE_CHECKING:
    from shary.console.view import View
    from shary.team import Team
    from shary.team.spec import TeamSpec

TEAM_KINDS = ("teleoperate", "robot-breakpoint", "clear-robot-breakpoint", "cancel-team-task")
"""Operator kinds only a team run carries out (``take-control``, ``hand-back``, ``answer``
and ``cancel`` exist for single robots too)."""
BREAK_EVENTS = ("question", "answer", "respawn", "associate", "control", "help-request",
                "task-failed", "goal-over")
"""Team events a run-level breakpoint may name besides acts (the run pauses after one)."""
CHUNK = 0.1
"""Simulated seconds between two looks at the console (as in ``sim``'s runs)."""


def roster(team: Team, elsewhere: Collection[str] = ()) -> dict[str, Any]:
    """The ``team`` row a run records when it starts: every member (robots with the atomic
    tasks they can be teleoperated with) and every team task, so that the page shows the
    whole team and the Task Manager's whole table from the start.  ``elsewhere``: the
    members that run in processes of their own (a distributed run: ``"process": "own"``,
    and the page offers no action that only their own process may take)."""
    members: list[dict[str, Any]] = []  # a list: the file's order (a log sorts its keys)
    for name, agent in team.agents.items():
        spec = agent.spec
        about: dict[str, Any] = {"name": name, "kind": spec.kind, "skills": list(spec.skills)}
        if spec.services:
            about["services"] = list(spec.services)
        if spec.remote:
            about["remote"] = True
        if name in elsewhere:
            about["process"] = "own"
        sup = getattr(agent, "sup", None)
        if sup is not None:
            world = set(agent.world.names())  # type: ignore[attr-defined]
            about["atomic"] = {a: list(t.params) for a, t in sup.library.atomic.items()
                               if a in world}
        members.append(about)
    tasks = [{"name": t.name, "skill": t.spec.skill, "after": list(t.spec.after)}
             for t in team.tasks.tasks.values()]
    return {"team": team.spec.name, "members": members, "tasks": tasks}


class TeamSteering:
    """What an operator may do to a team run (see the module's docstring)."""

    def __init__(self) -> None:
        self.team: Team | None = None
        self.stops: set[str] = set()
        """Robots with an operator's breakpoint."""
        self.held: dict[str, tuple[Request, Reporter, Executor]] = {}
        """Robot -> the atomic task it stopped before."""

    def attach(self, team: Team) -> None:
        """The run's team (on the run's thread, before it starts): wrap each robot's
        executors so that a breakpoint can stop it between two atomic tasks."""
        self.team = team
        for name, agent in team.agents.items():
            world = getattr(agent, "world", None)
            if world is not None:
                for atomic in world.names():
                    world.register(atomic, _Stop(self, name, world.get(atomic)))

    # -- checks, on the server's thread -------------------------------------------------

    def check(self, message: dict[str, Any], view: View) -> str | None:
        """Why a message cannot be carried out now (None: it can); the run's own controls
        (pause, step, speed, breakpoints) are :class:`~shary.console.live.LiveRun`'s."""
        kind = message["kind"]
        team = view.team
        members = {name: change[2] for name, change in team.members.items()}

        def is_(name: str | None, kind: str, what: str) -> str | None:
            if name is None:
                return f"say which {what} ('{'person' if what == 'person' else 'agent'}')"
            if members.get(name) != kind:
                return f"{name} is not a {what} of this team"
            return None

        if kind == "answer":
            return self._check_answer(message, view, is_)
        if kind == "act":
            return ("a team's people answer questions: answer one with its 'question' and "
                    "'text'")
        if kind == "seek":
            return "a live run cannot seek: open its log with 'shary serve --replay'"
        if kind in ("take-control", "hand-back", "teleoperate"):
            robot, person = message["agent"], message.get("person")
            why = is_(robot, "robot", "robot") or is_(person, "human", "person")
            if why:
                return why
            mode, by = team.control.get(robot, ["system", None])
            if kind == "take-control" and mode == "user":
                return f"{robot} is already driven by {by}"
            if kind != "take-control" and (mode != "user" or by != person):
                return (f"{robot} is not driven by {person}" +
                        (f" but by {by}" if mode == "user" else "") + " (take control first)")
            if kind == "teleoperate":
                return _check_atomic(robot, message, team.members[robot][3].get("atomic"))
        elif kind in ("robot-breakpoint", "clear-robot-breakpoint"):
            why = is_(message["agent"], "robot", "robot")
            if why:
                return why
            on = team.breaks.get(message["agent"], ["cleared"])[0] != "cleared"
            if on == (kind == "robot-breakpoint"):
                return f"{message['agent']} has {'a' if on else 'no'} breakpoint already"
        elif kind == "cancel-team-task":
            task = team.tasks.get(message["team_task"])
            if task is None or task["state"] not in ("offered", "running"):
                return f"team task {message['team_task']} is not offered or running"
        elif kind == "cancel":
            task = view.tasks.get(message["task"])
            if task is None or task["outcome"] is not None:
                return f"task {message['task']} is not running"
        else:
            return f"{kind} is not an action on a team (it acts on a JAHRVIS shared plan)"
        return None

    @staticmethod
    def _check_answer(message: dict[str, Any], view: View,
                      is_: Callable[[str | None, str, str], str | None]) -> str | None:
        qid = message.get("question")
        if qid is None:
            return "a team's questions are answered with 'question' and 'text'"
        question = view.team.questions.get(qid)
        if question is None:
            return f"question {qid} is not open (answered or expired)"
        person, text = message["agent"], message["text"]
        why = is_(person, "human", "person")
        if why:
            return why
        if question["holder"] != person:
            return f"question {qid} is put to {question['holder'] or 'nobody now'}, not {person}"
        if question["type"] == "yes-no" and text not in ("yes", "no"):
            return f"question {qid} is a yes-no question, not {text!r}"
        if question["type"] != "free-text" and question["choices"] and \
                text not in question["choices"]:
            return f"question {qid} takes one of {', '.join(question['choices'])}, not {text!r}"
        return None

    # -- actions, on the run's thread ---------------------------------------------------

    def perform(self, message: dict[str, Any], by: str) -> None:
        """Carry out a checked message through the team's ports (logged already)."""
        team = self.team
        if team is None:
            return
        kind = message["kind"]
        why: str | None = None
        if kind == "answer":
            proxy = team.human(message["agent"])
            if any(q.id == message["question"] for q in proxy.questions):
                proxy.answer(message["question"], message["text"])
            else:
                why = f"{proxy.name} no longer has question {message['question']}"
        elif kind == "take-control":
            team.take_control(message["person"], message["agent"])
        elif kind == "hand-back":
            team.hand_back(message["person"], message["agent"])
        elif kind == "teleoperate":
            team.robot(message["agent"]).teleoperate(message["person"], message["atomic"],
                                                     dict(message.get("args") or {}))
        elif kind == "robot-breakpoint":
            self.stops.add(message["agent"])
            team.record("robot-breakpoint", agent=message["agent"], state="set", by=by)
        elif kind == "clear-robot-breakpoint":
            self._clear(message["agent"], by)
        elif kind == "cancel-team-task":
            why = team.tasks.withdraw(message["team_task"], f"cancelled by the operator {by}")
        elif kind == "cancel":
            robot = team.robot(message["task"].rpartition("/")[0])
            robot.sup.cancel_task(message["task"], f"cancelled by the operator {by}")
        if why is not None:
            team.record("operator-refused", agent=by, action=kind, reason=why)

    def _clear(self, robot: str, by: str) -> None:
        self.stops.discard(robot)
        held = self.held.pop(robot, None)
        assert self.team is not None
        self.team.record("robot-breakpoint", agent=robot, state="cleared", by=by,
                         resumes=held[0].atomic if held else None)
        if held is not None:
            request, reporter, inner = held
            inner.start(request, reporter)

    def stopping(self, robot: str) -> bool:
        """Whether ``robot``'s next atomic task waits (a breakpoint, not in user mode)."""
        team = self.team
        return robot in self.stops and team is not None and \
            getattr(team.agents[robot], "mode", None) != USER


def _check_atomic(robot: str, message: dict[str, Any],
                  atomic: dict[str, list[str]] | None) -> str | None:
    """A teleoperated atomic task is one of the robot's, with exactly its parameters."""
    name, args = message.get("atomic"), message.get("args") or {}
    if not atomic:
        return f"{robot} says of no atomic task it can be teleoperated with"
    if name not in atomic:
        return f"{robot} has no atomic task {name!r} (it has {', '.join(sorted(atomic))})"
    params = atomic[name]
    if sorted(args) != sorted(params):
        return (f"{name} takes {', '.join(params) or 'nothing'}, "
                f"not {', '.join(sorted(args)) or 'nothing'}")
    return None


class _Stop:
    """A robot's executor with the operator's breakpoint in front of it."""

    __slots__ = ("steering", "robot", "inner")

    def __init__(self, steering: TeamSteering, robot: str, inner: Executor | None):
        self.steering = steering
        self.robot = robot
        self.inner = inner

    def start(self, request: Request, reporter: Reporter) -> None:
        steering = self.steering
        assert self.inner is not None and steering.team is not None
        if steering.stopping(self.robot) and self.robot not in steering.held:
            steering.held[self.robot] = (request, reporter, self.inner)
            steering.team.record("robot-breakpoint", task=request.node, agent=self.robot,
                                 state="stopped", before=request.atomic)
            return
        self.inner.start(request, reporter)

    def cancel(self, request: Request) -> None:
        held = self.steering.held.get(self.robot)
        if held is not None and held[0].id == request.id:
            del self.steering.held[self.robot]
            held[1].cancelled(request, "cancelled at the operator's breakpoint")
        elif self.inner is not None:
            self.inner.cancel(request)


# -- a team file run alone -------------------------------------------------------------


@dataclass
class TeamRunResult:
    """How a team file's goal ended (a team file states no expectations: done passes)."""

    team: str
    outcome: str | None
    end: float
    outputs: dict[str, str] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        passed = self.outcome == "done"
        return {"team": self.team, "passed": passed, "outcome": self.outcome,
                "simulated_seconds": round(self.end, 3), "outputs": self.outputs,
                "differences": [] if passed else
                [f"the goal is {self.outcome or 'not over'} at {self.end:.1f}s"]}


class _Observed:
    """The context log, each event also shown to the console."""

    def __init__(self, log: Any, console: Any):
        self.log = log
        self.console = console
        self.path = log.path  # the Context Manager reads the log's file

    def record(self, t: float, kind: str, *, task: str | None = None,
               agent: str | None = None, **data: Any) -> int:
        row = self.log.record(t, kind, task=task, agent=agent, **data)
        self.console.observe(t, kind, task, agent, data)
        return row

    def flush(self) -> None:
        self.log.flush()


def refuse_robots(spec: TeamSpec) -> str | None:
    """Why a team file cannot run alone: its robots need a world."""
    robots = [a.name for a in spec.agents.values() if a.kind == "robot"]
    if not robots:
        return None
    return (f"{robots[0]} is a robot: its atomic tasks need a world, which a team file "
            "alone does not give; run the team in a seam-welding scenario (a scenario with "
            "'site: seam-welding' and 'team: FILE', e.g. shary serve weld-nominal)")


def run_team(spec: TeamSpec, console: Any, *, out: Path, seed: int = 0,
             limit: float = 3600.0) -> TeamRunResult:
    """Run a team of people and software agents on a simulated clock under the console,
    until the goal is over and nothing is due, or ``limit``; write ``log.sqlite``,
    ``timeline.svg`` and ``summary.json`` to ``out``."""
    from shary.kernel.loop import EventLoop
    from shary.log.contextlog import ContextLog
    from shary.log.timeline import write_timeline
    from shary.team import Team
    from userfiles.outputs import output_folder, write_output

    output_folder(out)
    (out / "log.sqlite").unlink(missing_ok=True)
    loop = EventLoop(seed=seed)
    log = ContextLog(out / "log.sqlite", seed=seed)
    try:
        team = Team(spec, loop=loop, log=_Observed(log, console))
        team.record("team", **roster(team))
        console.attach(team)
        team.start()
        while loop.now() < limit - 1e-9:
            loop.advance(min(CHUNK, limit - loop.now()))
            console.between(loop.now())
            if team.tasks.outcome is not None and loop.clock.next_due() is None:
                break
        team.record("run-end", team=spec.name)
        log.flush()
    finally:
        log.close()
    result = TeamRunResult(spec.name, team.tasks.outcome, loop.now())
    write_timeline(out / "log.sqlite", out / "timeline.svg", title=spec.name)
    result.outputs = {"log": str(out / "log.sqlite"), "timeline": str(out / "timeline.svg"),
                      "summary": str(out / "summary.json")}
    write_output(out / "summary.json", json.dumps(result.summary(), indent=2) + "\n")
    return result

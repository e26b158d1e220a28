"""A live run behind the console: run in its own thread, steered between steps.

The engine runs on one loop and one clock, with no threads in the core; the
console does not change that.  The whole run (world, supervisor, loop) lives
in one worker thread, started when the first page connects, and the server's
asyncio loop lives in the main thread.  They meet at :class:`Attachment`,
which the run's driver (``sim.run.run_scenario(console=…)``) calls:

* ``attach(supervisor)`` once, to hand over the supervisor's ports
  (``receive_act``, ``record``, ``cancel_task``, the library's schemes);
* ``observe(...)`` for every event the run logs: forwarded to the server's
  loop, and checked against the breakpoints;
* ``between(now)`` after every step of the clock: where operator commands run
  (on the run's own thread, so the engine is never touched from elsewhere),
  where pause and step wait, and where the run is paced to the chosen speed.

Operator commands are queued closures run at the next ``between``; so an
answer sent while the run is paused is delivered as soon as it resumes, in
the order it was sent, and is logged (with who sent it) at once.
"""

from __future__ import annotations

import asyncio
import itertools
import queue
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from shary.console.operator import RUN_CONTROLS
from shary.console.ports import Feed, StatusFeed
from shary.console.teamlive import BREAK_EVENTS, TEAM_KINDS, TeamSteering
from shary.console.view import View
from shary.log.contextlog import LogEvent
from shary.statechart.acts import ACT_TYPES, builtin_acts
from shary.statechart.model import Scheme

Runner = Callable[["Attachment"], Any]
"""Runs the scenario with the attachment (``run_scenario(path, console=attachment)``)
and returns its result (an object with ``summary()``)."""
POLL = 0.05
"""Wall seconds between two looks at the command queue while paused."""


class StopRun(Exception):
    """Raised inside the run when the server stops: the run ends, its log is kept."""


class Attachment:
    """The run's side of the console (see the module's docstring)."""

    def __init__(self, live: LiveRun):
        self.live = live
        self.sup: Any = None
        self._seq = itertools.count(1)

    def attach(self, supervisor: Any) -> None:
        """The supervisor's ports, or a team's (:class:`~shary.team.Team`: then the live
        run's :class:`~shary.console.teamlive.TeamSteering` acts on it)."""
        self.sup = supervisor
        if self.live.steering is not None:
            self.live.steering.attach(supervisor)

    def observe(self, t: float, kind: str, task: str | None, agent: str | None,
                data: dict[str, Any]) -> None:
        live = self.live
        hit = data.get("act") if kind == "act" else kind if kind in BREAK_EVENTS else None
        if hit is not None and hit in live.breakpoints:
            with live.lock:
                live.paused = True
                live.stopped_at = f"breakpoint {hit} at {t:.1f} s"
        elif kind == "plan-task" and live.plan_breaks and (
                (data.get("state"), agent) in live.plan_breaks
                or (data.get("state"), None) in live.plan_breaks):
            with live.lock:
                live.paused = True
                live.stopped_at = (f"breakpoint {data.get('state')}: {data.get('name')} in "
                                   f"{agent}'s view at {t:.1f} s")
        live.post(live.feed, LogEvent(next(self._seq), t, kind, task, agent, dict(data)))

    def between(self, now: float) -> None:
        self.live.between(now)


class LiveRun:
    """A scenario run live under the console: the :class:`~shary.console.ports.RunPort`
    of a simulated run (pause, step, speed, breakpoints, acts, cancel)."""

    mode = "live"

    def __init__(self, title: str, runner: Runner, folder: Path | None, *,
                 schemes: Callable[[str], Scheme | None], speed: float = 1.0,
                 paused: bool = False, steering: TeamSteering | None = None):
        self.title = title
        self.folder = folder
        self._runner = runner
        self._schemes = schemes
        self.speed = speed
        self.paused = paused
        self.stopped_at = "paused at the start: press Resume" if paused else ""
        self.breakpoints: set[str] = set()
        self.plan_breaks: set[tuple[str, str | None]] = set()
        """(state, view) of a shared plan's tasks to pause at (view None: any)."""
        self.steering = steering
        """A team run's operator actions (None: a single SHARY robot's run)."""
        self.state = "waiting"
        self.verdict: dict[str, Any] | None = None
        self.summary: dict[str, Any] | None = None
        """The run's own summary (``result.summary()``) once it has ended by itself."""
        self.ended: Callable[[dict[str, Any]], None] | None = None
        """Called on the run's thread with :attr:`summary` when the run has ended: the
        command that serves it says the verdict and the files written on its terminal."""
        self._commands: queue.SimpleQueue[Callable[[], None]] = queue.SimpleQueue()
        self._step = False
        self._closing = threading.Event()
        self._pace: tuple[float, float] | None = None  # (wall, simulated) at the last change
        self._thread: threading.Thread | None = None
        self.lock = threading.Lock()
        """Guards pause, step and speed, set from the server's thread and read by the run's."""
        self._loop: asyncio.AbstractEventLoop | None = None
        self.attachment = Attachment(self)
        self.feed: Feed = lambda event: None
        self._status: StatusFeed = lambda status: None

    # -- the port ---------------------------------------------------------------------

    def scheme(self, name: str) -> Scheme | None:
        return self._schemes(name)

    def start(self, feed: Feed, status: StatusFeed) -> None:
        """Start the run's thread (the server calls this when the first page connects)."""
        if self._thread is not None:
            return
        self._loop = asyncio.get_running_loop()
        self.feed, self._status = feed, status
        self.state = "running"
        self._thread = threading.Thread(target=self._run, name="shary-run", daemon=True)
        self._thread.start()
        self.tell()

    def status(self) -> dict[str, Any]:
        state = "paused" if self.paused and self.state == "running" else self.state
        return {"mode": self.mode, "state": state, "speed": self.speed,
                "breakpoints": sorted(self.breakpoints), "why": self.stopped_at,
                "plan_breakpoints": sorted([s, v] for s, v in self.plan_breaks),
                "verdict": self.verdict}

    def tell(self) -> None:
        self.post(self._status, self.status())

    def post(self, fn: Callable[..., None], *args: Any) -> None:
        """Call ``fn`` on the server's loop (from any thread)."""
        if self._loop is not None and not self._loop.is_closed():
            try:
                self._loop.call_soon_threadsafe(fn, *args)
            except RuntimeError:  # the loop closed meanwhile: nobody is watching
                pass

    def handle(self, message: dict[str, Any], view: View) -> str | None:
        kind, by = message["kind"], message["by"]
        if self.state in ("ended", "error"):
            return "the run is over: nothing can be changed (open its log with --replay)"
        if self.state == "waiting":
            return "the run has not started yet"
        refusal = (self.steering.check(message, view)
                   if self.steering is not None and kind not in RUN_CONTROLS
                   else self._check(message, view))
        if refusal is not None:
            return refusal
        fields = {("for_agent" if k == "agent" else k): v for k, v in message.items()
                  if k not in ("kind", "by", "id")}
        self._submit(lambda: self.attachment.sup.record("operator", agent=by, action=kind,
                                                        **fields))
        if kind in RUN_CONTROLS:
            self._control(kind, message)
        elif self.steering is not None:
            steering = self.steering
            self._submit(lambda: steering.perform(message, by))
        elif kind in ("answer", "act"):
            self._submit(lambda: self.attachment.sup.receive_act(
                message["agent"], message["act"], task=message.get("task")))
        elif kind == "cancel":
            self._submit(lambda: self.attachment.sup.cancel_task(
                message["task"], f"cancelled by the operator {by}"))
        elif kind == "human-action":
            name, objects = view.plans.actions[message["plan_task"]]
            self._submit(lambda: self._report(message["agent"], name, objects, by))
        return None

    def _report(self, agent: str, action: str, objects: list[Any], by: str) -> None:
        """An operator's report of a person's action, through the recognizer's port."""
        try:
            self.attachment.sup.recognizer.report(agent, action, objects, by)
        except (AttributeError, ValueError) as err:
            self.attachment.sup.record("operator-refused", agent=by, action="human-action",
                                       reason=str(err))

    def refused(self, by: str, action: str, reason: str) -> None:
        if self.state == "running":
            self._submit(lambda: self.attachment.sup.record(
                "operator-refused", agent=by, action=action, reason=reason))
        else:  # the log is closed (or not open yet): say it where the server's user sees
            print(f"console: refused {action!r} from {by}: {reason}", file=sys.stderr)

    def close(self) -> None:
        self._closing.set()
        if self._thread is not None:
            self._thread.join(timeout=10)

    # -- checks, against the console's picture of the run --------------------------------

    def _check(self, message: dict[str, Any], view: View) -> str | None:
        kind = message["kind"]
        if kind == "answer" and "task" in message:
            question = view.questions.get(message["task"])
            if question is None:
                return f"task {message['task']} asks no question now"
            if message["agent"] not in question[3]:
                return (f"task {message['task']} asks {', '.join(question[3])}, "
                        f"not {message['agent']}")
            if message["act"] not in question[4]:
                return (f"task {message['task']} waits for {' or '.join(question[4])}, "
                        f"not {message['act']}")
        elif kind == "act":
            if view.agents.get(message["agent"]) != "human":
                return f"{message['agent']} is not a person of this run"
            if message["act"] not in ACT_TYPES and message["act"] not in builtin_acts():
                return f"{message['act']} is not an act"
        elif kind == "cancel":
            task = view.tasks.get(message["task"])
            if task is None or task["outcome"] is not None:
                return f"task {message['task']} is not running"
        elif kind == "human-action":
            return _check_report(message, view)
        elif kind in ("breakpoint", "clear-breakpoint") and "agent" in message \
                and message["agent"] not in view.agents:
            return f"{message['agent']} is not an agent of this run"
        elif kind in TEAM_KINDS or "question" in message:
            return (f"{kind} acts on an HRI/OS team, and this run is one SHARY robot's "
                    "(a team runs with 'shary serve weld-…' or 'shary serve --team FILE')")
        elif kind in ("take-control", "hand-back"):
            return ("this run has no control-authority port: a simulated SHARY robot answers "
                    "to its own supervisor only (control authority comes with HRI/OS teams)")
        elif kind == "seek":
            return "a live run cannot seek: open its log with 'shary serve --replay'"
        return None

    def _control(self, kind: str, message: dict[str, Any]) -> None:
        with self.lock:
            if kind == "pause":
                self.paused, self.stopped_at = True, "paused by the operator"
            elif kind == "resume":
                self.paused, self.stopped_at, self._pace = False, "", None
            elif kind == "step":
                self.paused, self._step, self.stopped_at = True, True, "stepping"
            elif kind == "speed":
                self.speed, self._pace = float(message["value"]), None
            elif kind == "breakpoint" and "state" in message:
                self.plan_breaks.add((message["state"], message.get("agent")))
            elif kind == "clear-breakpoint" and "state" in message:
                self.plan_breaks.discard((message["state"], message.get("agent")))
            elif kind == "breakpoint":
                self.breakpoints.add(message["act"])
            elif kind == "clear-breakpoint":
                self.breakpoints.discard(message["act"])
        self.tell()

    def _submit(self, command: Callable[[], None]) -> None:
        self._commands.put(command)

    # -- the run's thread ------------------------------------------------------------

    def _run(self) -> None:
        try:
            result = self._runner(self.attachment)
        except StopRun:
            self.state = "ended"
            self.verdict = {"passed": False, "differences": ["stopped with the server"]}
        except Exception as err:  # noqa: BLE001 -- shown on the page and the terminal
            self.state = "error"
            self.verdict = {"passed": False, "differences": [f"{type(err).__name__}: {err}"]}
            print(f"console: the run failed: {type(err).__name__}: {err}", file=sys.stderr)
        else:
            self.state = "ended"
            self.summary = summary = result.summary()
            self.verdict = {"passed": summary.get("passed"),
                            "differences": summary.get("differences", [])}
            if self.ended is not None:
                self.ended(summary)
        self.tell()

    def between(self, now: float) -> None:
        """Run queued commands; wait while paused; keep to the chosen speed."""
        self._drain()
        stepped = told = False
        while True:
            if self._closing.is_set():
                raise StopRun
            with self.lock:
                if self._step:
                    self._step, stepped = False, True
                    break
                if not self.paused:
                    break
            if not told:
                self.tell()
                told = True
            time.sleep(POLL)
            self._drain()
        if stepped:
            self.tell()
            return
        if self.speed > 0:
            wall = time.perf_counter()
            if self._pace is None:
                self._pace = (wall, now)
            due = self._pace[0] + (now - self._pace[1]) / self.speed
            while wall < due and not self._closing.is_set() and not self.paused:
                time.sleep(min(POLL, due - wall))
                self._drain()
                wall = time.perf_counter()

    def _drain(self) -> None:
        while True:
            try:
                command = self._commands.get_nowait()
            except queue.Empty:
                return
            try:
                command()
            except (KeyError, ValueError) as err:  # e.g. the task ended meanwhile
                print(f"console: an operator's command failed: {err}", file=sys.stderr)


DUE = ("TODO", "ONGOING", "NOT_STARTING", "NOT_FINISHED")
"""A shared plan's task states (in the robot's view) in which its agent may be doing it."""


def _check_report(message: dict[str, Any], view: View) -> str | None:
    """Whether an operator may report that a person did a task of the plan: a task of
    the plan, theirs, due now, with its values known."""
    plans, task, agent = view.plans, message["plan_task"], message["agent"]
    if task not in plans.actions:
        return f"{task} is not a task of a shared plan of this run"
    if agent not in plans.agents.get(task, "").split("|"):
        return f"{task} is {plans.agents.get(task) or 'nobody'}'s to do, not {agent}'s"
    robot = plans.views(task)[0] if plans.views(task) else ""
    state = plans.states.get((task, robot), "PLANNED")
    if state not in DUE:
        return f"{plans.labels.get(task, task)} is {state}, not due: nothing to report"
    if None in plans.actions[task][1]:
        return f"{plans.labels.get(task, task)} has values not chosen yet"
    return None

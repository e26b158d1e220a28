"""A distributed team under the console: ``shary team up … --console``.

The console shows a team spread over processes from the managers' process,
where :attr:`~shary.transport.distributed.Conductor.records` merges every
process's log rows live (:mod:`shary.transport.logshare`).  Those rows go
through the same :class:`~shary.console.live.Attachment` (breakpoints, then
the server's :class:`~shary.console.view.View`) as a run in one process, so
the page is the same page: every agent's block, the team tasks, the
delegations, the questions with their pictures (the log folder is the run's
folder), the robots' task trees and scheme configurations (their rows come
from the robots' processes), the timeline.

What the managers' process can honestly do, it does, on the conductor's
thread at :meth:`DistributedRun.gate` (between two steps of the shared
clock, when every member is idle): pause, resume, step and speed of the
shared clock, run breakpoints (every row of a step has reached the managers
before the clock moves on, since log records are counted in the barrier's
balance), and cancelling a team task (:meth:`~shary.team.tasks.TaskManager.withdraw`:
the Task Manager is here; the holder, in its own process, is told and stops).
A person's answer, control authority, teleoperation, a robot's breakpoint or
one of its SHARY tasks belong to a process elsewhere: :class:`DistributedSteering`
refuses them with the reason, rather than forging that agent's messages from here.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from shary.console.live import POLL, LiveRun, StopRun
from shary.console.teamlive import TeamSteering
from shary.log.contextlog import LogEvent
from shary.statechart.model import Scheme

if TYPE_CHECKING:
    from shary.console.view import View
    from shary.team import Team

ELSEWHERE = {
    "answer": "{agent} runs in its own process: answer from that person's own interface "
              "(shary agent {agent})",
    "take-control": "{agent} runs in its own process: control authority is taken from the "
                    "person's own interface, not from the managers' machine",
    "hand-back": "{agent} runs in its own process: control is handed back from the person's "
                 "own interface, not from the managers' machine",
    "teleoperate": "{agent} runs in its own process: teleoperate it from the driving "
                   "person's own interface",
    "robot-breakpoint": "{agent} runs in its own process: stop it from its own process "
                        "(a breakpoint on the shared clock stops the whole team from here)",
    "clear-robot-breakpoint": "{agent} runs in its own process: no breakpoint is held here",
    "cancel": "{agent}'s SHARY tasks run in its own process: cancel its team task here "
              "(cancel-team-task), or the task from the robot's own process",
}
"""Why an action on an agent of another process is refused on the managers' console."""


class DistributedSteering:
    """What an operator may do to a distributed team from the managers' process (see the
    module's docstring); the run's own controls are :class:`LiveRun`'s."""

    def __init__(self) -> None:
        self.team: Team | None = None

    def attach(self, team: Team) -> None:
        self.team = team

    def check(self, message: dict[str, Any], view: View) -> str | None:
        """Why not (None: it can be done here), checked against the page's picture."""
        kind = message["kind"]
        if kind == "cancel-team-task":
            task = view.team.tasks.get(message["team_task"])
            if task is None or task["state"] not in ("offered", "running"):
                return f"team task {message['team_task']} is not offered or running"
            return None
        why = TeamSteering().check(message, view)  # what is wrong with it, in any team run
        if why is None and kind in ELSEWHERE:  # right, but not the managers' to do
            agent = message["task"].rpartition("/")[0] if kind == "cancel" \
                else message["agent"]
            why = ELSEWHERE[kind].format(agent=agent)
        return why

    def perform(self, message: dict[str, Any], by: str) -> None:
        """Carry out a checked message (on the conductor's thread; logged already)."""
        team = self.team
        if team is None or message["kind"] != "cancel-team-task":
            return
        why = team.tasks.withdraw(message["team_task"], f"cancelled by the operator {by}")
        if why is not None:
            team.record("operator-refused", agent=by, action="cancel-team-task", reason=why)


class DistributedRun(LiveRun):
    """The :class:`~shary.console.ports.RunPort` of a distributed team run: a
    :class:`LiveRun` whose runner is ``shary team up``'s run on the managers' side, fed
    by the merged records, held at :meth:`gate` rather than at ``between``."""

    def __init__(self, title: str, runner: Callable[[Any], Any], folder: Path, *,
                 schemes: Callable[[str], Scheme | None], speed: float = 1.0,
                 paused: bool = False):
        super().__init__(title, runner, folder, schemes=schemes, speed=speed, paused=paused,
                         steering=DistributedSteering())  # type: ignore[arg-type]
        self._held = False

    def watch(self, conductor: Any) -> None:
        """Show ``conductor``'s merged records (those so far, then each as it comes) and
        steer its team; called on the conductor's thread, which is the run's."""
        self.attachment.attach(conductor.team)
        conductor.gate = self.gate
        records = conductor.records

        def observe(e: LogEvent) -> None:
            self.attachment.observe(e.time, e.kind, e.task, e.agent, e.data)

        for event in list(records.events):
            observe(event)
        records.listeners.append(observe)

    def gate(self, now: float, next_at: float) -> float:
        """Between two steps of the shared clock: run the operator's commands, hold while
        paused, keep to the chosen speed; the wall seconds to hold, 0 to step."""
        if self._closing.is_set():
            raise StopRun
        if not self._commands.empty():
            self._drain()
            return POLL / 10  # they may have sent messages: the conductor looks again
        with self.lock:
            stepping, paused = self._step, self.paused
            if stepping:
                self._step, self._pace = False, None
        if stepping:
            self.tell()
            return 0.0
        if paused:
            if not self._held:
                self._held = True
                self.tell()
            return POLL
        self._held = False
        if self.speed > 0:
            wall = time.perf_counter()
            if self._pace is None:
                self._pace = (wall, now)
            due = self._pace[0] + (next_at - self._pace[1]) / self.speed
            if wall < due:
                return min(POLL, due - wall)
        return 0.0

"""Stopping shary on a robot without leaving the robot moving.

When shary stops (Ctrl-C, SIGTERM, its node shut down) its goals are still running at the
robot's servers: a navigation goal drives on until it arrives.  :func:`safe_stop` ends
everything in order before the node goes:

1. ``~/run_task`` takes no new goal; the agenda's goals and every task are cancelled,
   each with its ``task-end`` row (``outcome: cancelled``, the reason);
2. every robot goal in flight is cancelled at its server (one not yet acknowledged as
   soon as it is), and no new one is sent;
3. the loop runs on until each server has answered (the goal's result came: the cancel
   is ``confirmed``) or the goal's ``cancel`` deadline has passed (``unconfirmed``, and
   for a goal never acknowledged its ``ack`` deadline first), each a ``ros-cancel`` row;
4. every ``~/run_task`` goal is answered (CANCELED if its client asked for the cancel,
   ABORTED otherwise, verdict ``cancelled`` and the reason), and the node spins a little
   longer so that the answers leave;
5. a ``ros-stop`` row says what was cancelled and what was left.

A second signal during the stop (a second Ctrl-C) abandons the wait at once: what it
leaves (goals whose server has not answered) is in the row and in what
:func:`safe_stop` returns, for the command to say.  :class:`StopSignals` turns SIGINT
and SIGTERM into a request for this stop, and the second into that abandon;
:func:`sigterm_as_ctrl_c` makes SIGTERM a Ctrl-C for a command whose node's closing
stops it.
"""

from __future__ import annotations

import signal
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from types import FrameType
from typing import Any

FLUSH = 0.3
"""Seconds the node keeps spinning once every ``~/run_task`` goal is answered: the
results leave through rclpy's executor and DDS's reliable writers, which destroying the
node would cut short."""
STEP = 0.02
"""Seconds of each turn of the loop while the stop waits."""


@dataclass
class StopReport:
    """What a stop did: the goals cancelled (each with how its server answered), the
    tasks ended, and the goals left when the stop was abandoned."""

    reason: str
    cancelled: list[tuple[str, str]] = field(default_factory=list)
    """(goal, ``confirmed`` / ``unconfirmed`` / ``ended``) for each robot goal in flight."""
    tasks: list[str] = field(default_factory=list)
    left: list[str] = field(default_factory=list)
    """The goals whose server had not answered when a second signal abandoned the stop."""

    def lines(self) -> list[str]:
        """The report as a person reads it."""
        said = [f"stopping ({self.reason}): {len(self.tasks)} task(s) cancelled, "
                f"{len(self.cancelled)} robot goal(s) cancelled"]
        said += [f"  {goal}: {state}" for goal, state in self.cancelled]
        if self.left:
            said.append(f"abandoned the stop: left {len(self.left)} robot goal(s) whose "
                        f"cancel was not answered: {'; '.join(self.left)}")
        return said


def safe_stop(sup: Any, executors: Any, server: Any, loop: Any, reason: str) -> StopReport:
    """Stop a supervisor on ROS 2 as the module's docstring says; what it did."""
    report = StopReport(reason)
    _wall_time(loop)
    server.stopping = reason
    in_flight = list(executors.unsettled())
    for goal in sup.agenda.goals:
        sup.agenda.cancel(goal, reason)
    for node, run in list(sup.runs.items()):
        if not run.ended and run.parent is None:
            report.tasks.append(node)
            sup.cancel_task(node, reason)
    for run in [*sup.runs.values(), *sup.background.values()]:
        if not run.ended:
            report.tasks.append(run.node)
            run.cancel(reason)
    executors.stop(reason)
    in_flight += [g for g in executors.unsettled() if g not in in_flight]
    deadline = time.monotonic() + max(
        (g.task.deadlines["cancel"] + (g.task.deadlines["ack"] if g.phase == "ack" else 0)
         for g in in_flight), default=0.0) + 1.0
    try:
        while (executors.unsettled() or server.unanswered()) and time.monotonic() < deadline:
            loop.run_for(STEP)
        end = time.monotonic() + FLUSH
        while time.monotonic() < end:
            loop.run_for(STEP)
    except KeyboardInterrupt:
        report.left = [executors.describe(g) for g in executors.unsettled()]
    for goal in in_flight:
        report.cancelled.append((executors.describe(goal), _state(goal, report.left,
                                                                  executors.describe)))
    sup.record("ros-stop", reason=reason, tasks=report.tasks,
               goals=[f"{goal}: {state}" for goal, state in report.cancelled],
               left=report.left or None)
    if hasattr(sup.log, "flush"):  # written now: what follows the stop may be a crash
        sup.log.flush()
    return report


def _wall_time(loop: Any) -> None:
    """A stop runs on real time: a simulation's clock may be paused
    (:class:`~shary.ros.clock.RosClock`)."""
    follow_wall = getattr(loop.clock, "follow_wall", None)
    if follow_wall is not None:
        follow_wall()


def _state(goal: Any, left: list[str], describe: Any) -> str:
    """How a goal in flight ended in a stop."""
    if describe(goal) in left:
        return "left"
    if goal.unconfirmed:
        return "unconfirmed"
    if goal.phase != "over":
        return "unanswered"
    return "confirmed" if goal.cancel_sent else "ended"


class StopSignals:
    """SIGINT and SIGTERM ask for a safe stop (:attr:`requested` names the signal); a
    second one, while the stop runs, raises KeyboardInterrupt to abandon it.  Used as a
    context manager around a command's run (on the main thread); the previous handlers
    are put back on exit."""

    def __init__(self, loop: Any = None):
        self.loop = loop
        """Woken when a stop is asked for, so that it begins at once."""
        self.requested: str | None = None
        self._previous: dict[int, Any] = {}

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self.requested is not None:
            raise KeyboardInterrupt
        self.requested = signal.Signals(signum).name
        if self.loop is not None:
            _wall_time(self.loop)  # the loop's wait ends in real time, sim paused or not
            self.loop.call_soon_threadsafe(lambda: None)

    def __enter__(self) -> StopSignals:
        for signum in (signal.SIGINT, signal.SIGTERM):
            self._previous[signum] = signal.signal(signum, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)


@contextmanager
def sigterm_as_ctrl_c() -> Iterator[None]:
    """Within it, SIGTERM raises KeyboardInterrupt as Ctrl-C does: a command whose loop
    ends on Ctrl-C, and whose node's closing stops it safely, stops so on SIGTERM too
    (a parent that died: :mod:`shary.ros.lifeline`)."""
    def interrupt(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)

"""Log records shared: every member's context-log rows, live, in the managers' process.

Each process of a distributed team keeps its own context log (one SQLite
file per agent: that is the record, merged afterwards by ``shary log``).  A
member's log is wrapped in a :class:`SharedLog` whose tap turns every row into
a :class:`~shary.transport.messages.LogRecord` to the managers' address
:data:`LOGS`; the records leave with the port's outbox, after the member's
own commit, like every other message (so the managers never see a row the
member could still lose).  In the managers' process, a :class:`TeamRecords`
gathers its own rows and the members' into one view ordered by time: what a
console on the managers' machine shows, and what the managers read to tell a
member that comes back which robots it is associated with or controls.

The records bypass the port's own logging (a row about a row would never
end) and its injected faults (they copy the log; the link under test is the
team's messages).
"""

from __future__ import annotations

import bisect
import itertools
from collections.abc import Callable
from typing import Any

from shary.log.contextlog import LogEvent
from shary.transport.messages import LogRecord, Message

LOGS = "logs"
"""The managers' address for the members' log records."""
KEEP = 100_000
"""Rows the merged view keeps in memory, the newest (every process's log file keeps them
all): a team that runs for hours must not grow the managers' process without end."""

Tap = Callable[[float, str, "str | None", "str | None", dict[str, Any]], Any]
"""Told ``(time, kind, task, agent, data)`` for every row a log records."""


class SharedLog:
    """A process's context log (or none) whose rows also go to ``tap``.

    The same ``record``/``flush``/``close`` as :class:`~shary.log.contextlog.ContextLog`;
    ``path`` and the rest come from the log it wraps (absent without one, so a
    team without a log file builds no context manager).
    """

    def __init__(self, inner: Any, tap: Tap):
        self.inner = inner
        self.tap = tap

    def record(self, time: float, kind: str, *, task: str | None = None,
               agent: str | None = None, **data: Any) -> int:
        seq = self.inner.record(time, kind, task=task, agent=agent, **data) \
            if self.inner is not None else 0
        self.tap(time, kind, task, agent, data)
        return seq

    def flush(self) -> None:
        if self.inner is not None:
            self.inner.flush()

    def close(self) -> None:
        if self.inner is not None:
            self.inner.close()

    def __getattr__(self, name: str) -> Any:
        if name == "inner" or self.__dict__.get("inner") is None:
            raise AttributeError(name)
        return getattr(self.__dict__["inner"], name)


class Forwarder:
    """A member's tap: each row becomes a :class:`LogRecord` to the managers, queued on
    the port's outbox (rows recorded before the port exists wait for it)."""

    def __init__(self, name: str):
        self.name = name
        self.port: Any = None
        self._early: list[LogRecord] = []

    def __call__(self, time: float, kind: str, task: str | None, agent: str | None,
                 data: dict[str, Any]) -> None:
        record = LogRecord(self.name, LOGS, time=time, event=kind, task=task, agent=agent,
                           data=data)
        if self.port is None:
            self._early.append(record)
            return
        self.port.forward(record)

    def attach(self, port: Any) -> None:
        """The port exists: the rows kept so far leave with the next flush."""
        self.port = port
        early, self._early = self._early, []
        for record in early:
            port.forward(record)


class TeamRecords:
    """The live merged view of a team's logs, in the managers' process.

    ``events`` are :class:`~shary.log.contextlog.LogEvent` s ordered by time (rows of one
    time keep their arrival order; ``seq`` numbers them as they arrive), the
    newest ``keep`` of them (``dropped`` counts the older ones let go: the log
    files hold them); ``listeners`` hear each row as it comes (a console's
    feed).  ``by`` counts the rows per process.  Which robots are associated
    with or controlled by whom is kept from every row, dropped or not.
    """

    def __init__(self, keep: int = KEEP) -> None:
        self.keep = keep
        self.events: list[LogEvent] = []
        self._times: list[float] = []
        self._seq = itertools.count(1)
        self.listeners: list[Callable[[LogEvent], Any]] = []
        self.by: dict[str, int] = {}
        self.dropped = 0
        self._associated: dict[str, str] = {}
        self._controlled: dict[str, str] = {}

    def tap(self, process: str) -> Tap:
        """The tap for this process's own log (the managers' rows)."""
        def own(time: float, kind: str, task: str | None, agent: str | None,
                data: dict[str, Any]) -> None:
            self.add(process, time, kind, task, agent, data)
        return own

    def handle(self, message: Message) -> None:
        """A member's :class:`LogRecord` (the managers' :data:`LOGS` address)."""
        if isinstance(message, LogRecord):
            self.add(message.sender, message.time, message.event, message.task,
                     message.agent, message.data)

    def add(self, process: str, time: float, kind: str, task: str | None,
            agent: str | None, data: dict[str, Any]) -> None:
        event = LogEvent(next(self._seq), time, kind, task, agent, dict(data))
        at = bisect.bisect_right(self._times, time)
        self._times.insert(at, time)
        self.events.insert(at, event)
        self.by[process] = self.by.get(process, 0) + 1
        self._link(event)
        if len(self.events) > self.keep:  # a tenth at once: the cost of a cut is shared
            cut = len(self.events) - self.keep + self.keep // 10
            del self.events[:cut], self._times[:cut]
            self.dropped += cut
        for listener in self.listeners:
            listener(event)

    def _link(self, e: LogEvent) -> None:
        """Follow the robots' association and control rows (each robot's come from its
        own process, in its order)."""
        if e.agent is None:
            return
        if e.kind == "associate" and isinstance(e.data.get("requester"), str):
            self._associated[e.agent] = e.data["requester"]
        elif e.kind == "release":
            self._associated.pop(e.agent, None)
        elif e.kind == "control" and isinstance(e.data.get("by"), str):
            if e.data.get("mode") == "user":
                self._controlled[e.agent] = e.data["by"]
            else:
                self._controlled.pop(e.agent, None)

    def links(self) -> tuple[dict[str, str], dict[str, str]]:
        """From the rows so far: robot -> the person it is associated with, and robot ->
        the person controlling it (user mode), as the robots logged them."""
        return dict(self._associated), dict(self._controlled)

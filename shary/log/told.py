"""One context log, several audiences: :class:`Told`.

A run's events go to one log (a :class:`~shary.log.contextlog.ContextLog`, an in-memory
log, or none), and each is also told, in order, to listeners the engine does
not know: the simulated run's story and the console (``sim.run``), the ROS
views and the task server (``shary.ros``).  The engine is given a ``Told`` as
its log and never sees who listens.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

Listener = Callable[[float, str, "str | None", "str | None", dict[str, Any]], Any]
"""Told ``(time, kind, task, agent, data)`` for every event a run logs."""


class Told:
    """The context log ``log`` (None: nothing kept), each event also told to
    ``listeners`` in order."""

    def __init__(self, log: Any = None, *listeners: Listener):
        self.log = log
        self.listeners = list(listeners)
        if hasattr(log, "path"):
            self.path = log.path  # the Context Manager reads the log's file

    def record(self, t: float, kind: str, *, task: str | None = None,
               agent: str | None = None, **data: Any) -> Any:
        row = self.log.record(t, kind, task=task, agent=agent, **data) if self.log else None
        for listener in self.listeners:
            listener(t, kind, task, agent, data)
        return row

    def flush(self) -> None:
        if self.log is not None:
            self.log.flush()

"""What the console's views share: the agents, the timeline's items, the act/action
lines, and the changes that tell the page about them.

:class:`~shary.console.view.View` folds a run's events; the shared plan's part
(:mod:`shary.console.planview`) and the team's (:mod:`shary.console.teamview`) fold
theirs into the same picture through this base, so that none of them reaches into
another's internals.
"""

from __future__ import annotations

from collections import deque
from typing import Any

from shary.log.contextlog import LogEvent

Change = list[Any]
"""One change the page applies (``["state", "n4", "done"]``; see :mod:`shary.console.view`)."""

MAX_LINES = 300
"""Act/action lines a page is sent on joining (the newest); the log keeps them all."""


class ViewBase:
    """The agents, items and lines of one run's picture, each added with its change."""

    def __init__(self) -> None:
        self.agents: dict[str, str] = {}
        self.items: dict[str, list[Any]] = {}
        self.lines: deque[Change] = deque(maxlen=MAX_LINES)

    def agent(self, name: str | None, kind: str, out: list[Change]) -> None:
        """Make ``name`` known as an agent of ``kind`` (a plain ``agent`` learns its kind
        when an event tells it)."""
        if not name:
            return
        known = self.agents.get(name)
        if known is None or (known == "agent" and kind != "agent"):
            self.agents[name] = kind
            out.append(["agent", name, kind])

    def line(self, e: LogEvent, kind: str, text: str, out: list[Change]) -> None:
        """An act/action line for ``e`` (who is ``e``'s agent)."""
        line = ["line", e.time, e.agent or "", kind, text]
        self.lines.append(line)
        out.append(line)

    def add_item(self, item: str, lane: str, t0: float, label: str, cls: str,
                 out: list[Change]) -> None:
        """An item of the timeline in ``lane`` from ``t0``, open until :meth:`end_item`."""
        self.items[item] = [item, lane, t0, label, cls, None]
        out.append(["item", item, lane, t0, label, cls])

    def end_item(self, item: str, t1: float, cls: str, out: list[Change]) -> None:
        """Close an open item at ``t1`` with its final class (a closed one stays)."""
        found = self.items.get(item)
        if found is not None and found[5] is None:
            found[5] = t1
            found[4] = cls
            out.append(["item-end", item, t1, cls])

"""A recorded run behind the console: its context log, seen at any time with a slider.

The log is read once, checked row by row by the log's own reader (a damaged
or hostile file is refused as ``LOG:1:1: error: …`` before the server
starts), and kept in memory; the page's slider asks for a time, and the view
at that time is folded again from the first event, by the same
:class:`~shary.console.view.View` a live run uses.  Nothing is written: the
log is a record, so every steering message is refused (and said on the
server's terminal, as the log cannot take it).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any

from shary.console.ports import Feed, StatusFeed
from shary.console.view import Change, View
from shary.kernel.tasktree import replay_log
from shary.log.contextlog import LogEvent, stream_events
from shary.statechart.model import Scheme
from userfiles.errors import FileError


def named_schemes() -> Callable[[str], Scheme | None]:
    """Schemes by name as a log names them (the built-in ones, or a file's path); None for
    a name that cannot be loaded, whose task the page then shows as a list of states."""
    from shary.io.schemes import load_scheme

    @cache
    def lookup(name: str) -> Scheme | None:
        try:
            return load_scheme(name)
        except (FileError, OSError, ValueError, KeyError):
            return None
    return lookup


class Replay:
    """The :class:`~shary.console.ports.RunPort` of a logged run."""

    mode = "replay"

    def __init__(self, log: str | Path, schemes: Callable[[str], Scheme | None]):
        self.log = Path(log)
        self.title = f"{self.log.parent.name or self.log.name} (replay)"
        self.folder = self.log.resolve().parent
        with stream_events(self.log) as events:
            self.events: list[LogEvent] = list(events)
        replay_log(self.log)  # a tree the log cannot have grown is refused at its row
        self.end = self.events[-1].time if self.events else 0.0
        self._schemes = schemes

    def scheme(self, name: str) -> Scheme | None:
        return self._schemes(name)

    def start(self, feed: Feed, status: StatusFeed) -> None:
        status(self.status())

    def status(self) -> dict[str, Any]:
        return {"mode": self.mode, "state": "replay", "end": self.end}

    def view_at(self, t: float) -> View:
        """The view as it stood at time ``t`` (every event up to ``t`` included)."""
        view = View(self.scheme)
        for event in self.events:
            if event.time > t:
                break
            view.apply(event)
        return view

    def changes_at(self, t: float) -> list[Change]:
        view = self.view_at(t)
        return [["time", min(t, self.end)], *view.snapshot()[1:]]

    def handle(self, message: dict[str, Any], view: View) -> str | None:
        return f"a replay is a record: it cannot be steered ({message['kind']} refused)"

    def refused(self, by: str, action: str, reason: str) -> None:
        print(f"console: refused {action!r} from {by}: {reason}", file=sys.stderr)

    def close(self) -> None:
        pass

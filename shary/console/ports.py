"""What the console needs from a run: the port a live run and a replay both fill.

The console reads a run only as context-log events and acts on it only
through :class:`RunPort`; it never holds the engine's objects.  A team of
agents (JAHRVIS, HRI/OS) fills the same port: its events name their agents,
and the page groups everything per agent.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol

from shary.console.view import View
from shary.log.contextlog import LogEvent
from shary.statechart.model import Scheme

Feed = Callable[[LogEvent], None]
"""Where a run sends its events (called on the server's event loop)."""
StatusFeed = Callable[[dict[str, Any]], None]
"""Where a run sends its status: running, paused, speed, breakpoints, the verdict."""


class RunPort(Protocol):
    """A run seen by the console (see the module's docstring)."""

    mode: str
    """``live`` or ``replay``: the page offers the controls that fit."""
    title: str
    folder: Path | None
    """The run's folder: the only place the console serves files from (snapshots)."""

    def scheme(self, name: str) -> Scheme | None:
        """A scheme by name, to draw; None when the run cannot say."""

    def start(self, feed: Feed, status: StatusFeed) -> None:
        """Begin sending events and status (called once, on the server's loop)."""

    def handle(self, message: dict[str, Any], view: View) -> str | None:
        """Carry out a checked operator message; return why not, or None when done.

        ``view`` is the console's picture of the run (from its events), against
        which a message is checked: an answer must answer an open question.
        """

    def refused(self, by: str, action: str, reason: str) -> None:
        """Log a refused message with who sent it."""

    def close(self) -> None:
        """The server is stopping: stop the run, keep what it logged."""


SNAPSHOT = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,200}\.png$")
"""The names of a run's pictures (``snapshot-….png``, a team robot's camera ``k-10-01-….png``),
the only files of its folder the console reads."""


def run_file(folder: Path | None, name: object) -> Path | None:
    """A picture of the run's folder by name; None for anything else: no path, no other
    file, no link that leads out of the folder."""
    if folder is None or not isinstance(name, str) or not SNAPSHOT.match(name):
        return None
    root = folder.resolve()
    found = (root / name).resolve()
    if found.parent != root or not found.is_file():
        return None
    return found

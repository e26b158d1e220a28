"""Checking the engine against statechart tests written by others.

Two kinds of tests are found under a folder:

* SCION-style pairs, ``NAME.scxml`` and ``NAME.json`` with
  ``{"initialConfiguration": [...], "events": [{"event": {"name": ...},
  "after": ms, "nextConfiguration": [...]}]}``: the chart is started, its active
  atomic states compared with the initial configuration, then for each entry
  the clock moves on ``after`` milliseconds, the event is sent, and the active
  atomic states are compared with the next configuration (as sets);
* plain charts, ``NAME.scxml`` alone, which pass when they reach a final state
  named ``pass`` (time is advanced until no timer is left, within a limit).

Every chart goes the way a user's would: imported to scheme YAML, loaded and
checked from that text, compiled, run on a simulated clock.  A trace is a
user's file too: it is read safely and checked against
``shary/schemas/trace.schema.json``, and a broken one is refused with
positions (:class:`FileError`), not run.  A chart that loops (a livelock, a
zero-delay timer loop, or more than :data:`MAX_TIMER_EVENTS` timers) fails
with the reason, in bounded time.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from shary.io import schema
from shary.io.schemes import parse_scheme
from shary.io.scxml import import_scxml
from shary.statechart.clock import SimulatedClock
from shary.statechart.compiler import compile_scheme
from shary.statechart.instance import LivelockError
from userfiles.errors import FileError, Problem
from userfiles.yamlsafe import Located, load_text, read_text

PLAIN_CHART_TIME_LIMIT = 60.0
"""Simulated seconds a plain chart may take to reach ``pass``."""
MAX_TIMER_EVENTS = 100_000
"""Timer firings one chart may cause before it is failed as a timer loop."""

PASSED, REFUSED, MISMATCH, LOOPING = "passed", "refused", "mismatch", "looping"
"""The kinds of outcome: passed; refused at import (constructs named); ran but ended in
the wrong configuration; never settled (livelock or timer loop)."""


@dataclass(frozen=True)
class Outcome:
    """The result of one conformance test (``kind`` is one of :data:`PASSED` …)."""

    name: str
    passed: bool
    reason: str = ""
    kind: str = PASSED


class _TimerLoop(Exception):
    """More than :data:`MAX_TIMER_EVENTS` timers fired for one chart."""


def find_tests(folder: str | os.PathLike[str]) -> list[Path]:
    """Every ``.scxml`` chart under ``folder``, sorted."""
    return sorted(Path(folder).rglob("*.scxml"))


def run_test(chart: Path, root: Path | None = None) -> Outcome:
    """Run one chart (a SCION pair when its ``.json`` exists, else a plain chart).

    Raises :class:`FileError` when the chart's trace is not a valid trace.
    """
    name = str(chart.relative_to(root)) if root else str(chart)
    trace_file = chart.with_suffix(".json")
    trace = read_trace(trace_file) if trace_file.exists() else None
    try:
        text = import_scxml(chart)
        scheme = parse_scheme(load_text(text, f"{chart} (imported)"))
    except FileError as err:
        reasons = dict.fromkeys(p.message for p in err.problems)
        return Outcome(name, False, "refused: " + "; ".join(reasons), REFUSED)
    clock = SimulatedClock()
    timers = _Timers(clock)
    try:
        instance = compile_scheme(scheme).start(clock=clock)
        if trace is None:
            timers.advance(PLAIN_CHART_TIME_LIMIT, lambda: instance.finished)
            if "pass" in instance.configuration:
                return Outcome(name, True)
            return Outcome(name, False, f"ended in {sorted(instance.configuration)}, not "
                           "'pass'", MISMATCH)
        got = set(instance.configuration)
        if got != set(trace["initialConfiguration"]):
            return Outcome(name, False, f"initial configuration {sorted(got)}, expected "
                           f"{sorted(trace['initialConfiguration'])}", MISMATCH)
        for index, step in enumerate(trace.get("events", []), 1):
            if "after" in step:
                timers.advance(step["after"] / 1000.0)
            instance.send(step["event"]["name"])
            got = set(instance.configuration)
            if got != set(step["nextConfiguration"]):
                return Outcome(name, False, f"after event {index} ({step['event']['name']!r}): "
                               f"{sorted(got)}, expected {sorted(step['nextConfiguration'])}",
                               MISMATCH)
    except LivelockError as err:
        return Outcome(name, False, str(err), LOOPING)
    except _TimerLoop as err:
        return Outcome(name, False, str(err), LOOPING)
    return Outcome(name, True)


def read_trace(path: Path) -> dict:
    """A SCION trace, read safely and checked against its schema; :class:`FileError` if bad.

    The YAML reader gives the positions (and refuses hostile nesting, size and
    duplicate keys); the values are JSON's, so that ``1e15`` is a number and
    ``NaN`` or ``Infinity`` are not.
    """
    text = read_text(path)
    try:
        located = load_text(text, str(path))
    except FileError as err:
        if not err.problems[0].message.startswith("YAML syntax"):
            raise
        located = Located(str(path), None)
    try:
        located.data = json.loads(text, parse_constant=str)
    except ValueError as err:
        at = min(getattr(err, "pos", 0), len(text.rstrip()))
        line = text.count("\n", 0, at) + 1
        col = at - (text.rfind("\n", 0, at) + 1) + 1
        message = getattr(err, "msg", str(err))
        raise FileError([Problem(str(path), line, col, f"JSON syntax: {message}")]) from None
    problems = located.problems + schema.check(located, "trace")
    if problems:
        raise FileError(problems)
    return located.data


class _Timers:
    """Moves a chart's clock timer by timer, counting firings: a timer loop must end."""

    def __init__(self, clock: SimulatedClock):
        self.clock = clock
        self.fired = 0

    def advance(self, seconds: float, until: Callable[[], bool] | None = None) -> None:
        """Let ``seconds`` pass (or less, once ``until()`` holds)."""
        end = self.clock.now() + seconds
        while until is None or not until():
            due = self.clock.next_due()
            if due is None or due > end:
                break
            self.fired += self.clock.advance_to(due)
            if self.fired > MAX_TIMER_EVENTS:
                raise _TimerLoop(f"more than {MAX_TIMER_EVENTS} timer events by "
                                 f"{self.clock.now():g} s of simulated time (a timer loop)")
        if until is None:
            self.clock.advance_to(end)

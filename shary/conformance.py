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
checked from that text, compiled, run on a simulated clock.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

from shary.clock import SimulatedClock
from shary.compiler import compile_scheme
from shary.io.schemes import parse_scheme
from shary.io.scxml import import_scxml
from userfiles.errors import FileError
from userfiles.yamlsafe import load_text

PLAIN_CHART_TIME_LIMIT = 60.0
"""Simulated seconds a plain chart may take to reach ``pass``."""


@dataclass(frozen=True)
class Outcome:
    """The result of one conformance test."""

    name: str
    passed: bool
    reason: str = ""


def find_tests(folder: str | os.PathLike[str]) -> list[Path]:
    """Every ``.scxml`` chart under ``folder``, sorted."""
    return sorted(Path(folder).rglob("*.scxml"))


def run_test(chart: Path, root: Path | None = None) -> Outcome:
    """Run one chart (a SCION pair when its ``.json`` exists, else a plain chart)."""
    name = str(chart.relative_to(root)) if root else str(chart)
    try:
        text = import_scxml(chart)
        scheme = parse_scheme(load_text(text, f"{chart} (imported)"))
    except FileError as err:
        reasons = dict.fromkeys(p.message for p in err.problems)
        return Outcome(name, False, "refused: " + "; ".join(reasons))
    compiled = compile_scheme(scheme)
    clock = SimulatedClock()
    instance = compiled.start(clock=clock)
    trace = chart.with_suffix(".json")
    if not trace.exists():
        while not instance.finished and clock.now() < PLAIN_CHART_TIME_LIMIT:
            due = clock.next_due()
            if due is None:
                break
            clock.advance_to(due)
        if "pass" in instance.configuration:
            return Outcome(name, True)
        return Outcome(name, False, f"ended in {sorted(instance.configuration)}, not 'pass'")
    try:
        expected = json.loads(trace.read_text("utf-8"))
    except (OSError, ValueError) as err:
        return Outcome(name, False, f"unreadable trace {trace.name}: {err}")
    got = set(instance.configuration)
    if got != set(expected["initialConfiguration"]):
        return Outcome(name, False, f"initial configuration {sorted(got)}, expected "
                       f"{sorted(expected['initialConfiguration'])}")
    for index, step in enumerate(expected.get("events", []), 1):
        if "after" in step:
            clock.advance(step["after"] / 1000.0)
        instance.send(step["event"]["name"])
        got = set(instance.configuration)
        if got != set(step["nextConfiguration"]):
            return Outcome(name, False, f"after event {index} ({step['event']['name']!r}): "
                           f"{sorted(got)}, expected {sorted(step['nextConfiguration'])}")
    return Outcome(name, True)


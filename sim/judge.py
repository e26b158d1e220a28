"""A scenario's expected outcome, and the judge that compares a run with it.

A scenario file's ``expect`` section becomes an :class:`Expect`; a run (in one
process, :mod:`sim.run`, or over ROS 2, :mod:`sim.rosrun`) tells what it did as
a :class:`Happened`; :func:`judge` lists every difference in words.  It is its
own module because it changes when a new kind of expectation is added (a shared
plan's events, words said, recognitions), not when the scenario file's reading
and meaning checks (:mod:`sim.scenario`) do, and both run paths need it without
the reader.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class Expect:
    """A scenario's ``expect`` section: what the run must (and must not) do."""

    acts: tuple[str, ...] = ()
    no_acts: tuple[str, ...] = ()
    actions: tuple[str, ...] = ()
    no_actions: tuple[str, ...] = ()
    failed_actions: tuple[str, ...] = ()
    facts: tuple[tuple[Any, Any, Any], ...] = ()
    no_facts: tuple[tuple[Any, Any, Any], ...] = ()
    tasks: dict[str, str] = field(default_factory=dict)
    within: float | None = None
    plan: tuple[str, ...] = ()
    """A shared plan's events, in order (started, replan, achieved, failed)."""
    said: tuple[str, ...] = ()
    """Words the robot must say, in order (each a part of one sentence)."""
    task_states: tuple[tuple[str, str, str], ...] = ()
    """(view, task label, state) a shared plan's task must enter, in any order."""
    recognized: tuple[tuple[str, str, str], ...] = ()
    """(state, action, agent) the recognizer must report, in order."""


@dataclass(frozen=True)
class Happened:
    """What a run did, as the judge needs it."""

    acts: list[tuple[float, str, str]]          # time, agent, act
    actions: list[tuple[float, str, str, str]]  # time, agent, atomic, status ("started" …)
    tasks: dict[str, list[str]]                 # task name -> outcomes of its runs
    facts: set[tuple[str, str, str]]
    end: float
    plan: list[str] = field(default_factory=list)
    said: list[str] = field(default_factory=list)
    task_states: set[tuple[str, str, str]] = field(default_factory=set)
    recognized: list[tuple[str, str, str]] = field(default_factory=list)


def _in_order(wanted: Iterable[str], seen: list[str]) -> str | None:
    """The first wanted item not found after the previous ones, or None."""
    position = 0
    for item in wanted:
        try:
            position = seen.index(item, position) + 1
        except ValueError:
            return item
    return None


def judge(expect: Expect, happened: Happened) -> list[str]:
    """Every way the run differs from what the scenario expects, in words."""
    out = []
    acts = [act for _, _, act in happened.acts]
    missing = _in_order(expect.acts, acts)
    if missing is not None:
        out.append(f"expected the act {missing} (in the order {', '.join(expect.acts)}); "
                   f"acts were: {', '.join(acts) or 'none'}")
    for act in expect.no_acts:
        when = [f"{t:.1f}s" for t, _, a in happened.acts if a == act]
        if when:
            out.append(f"the act {act} must not happen; it did at {', '.join(when)}")
    done = [atomic for _, _, atomic, status in happened.actions if status == "done"]
    missing = _in_order(expect.actions, done)
    if missing is not None:
        out.append(f"expected the action {missing} done (in the order "
                   f"{', '.join(expect.actions)}); done were: {', '.join(done) or 'none'}")
    for atomic in expect.no_actions:
        when = [f"{t:.1f}s" for t, _, a, s in happened.actions if a == atomic and s == "started"]
        if when:
            out.append(f"the action {atomic} must not start; it did at {', '.join(when)}")
    failed = [atomic for _, _, atomic, status in happened.actions if status == "failed"]
    for atomic in expect.failed_actions:
        if atomic not in failed:
            out.append(f"expected the action {atomic} to fail; it did not")
    for fact in expect.facts:
        key = tuple(str(v) for v in fact)
        if key not in happened.facts:
            out.append(f"expected the fact {' '.join(key)} at the end; it does not hold")
    for fact in expect.no_facts:
        key = tuple(str(v) for v in fact)
        if key in happened.facts:
            out.append(f"the fact {' '.join(key)} must not hold at the end; it does")
    for task, outcome in expect.tasks.items():
        outcomes = happened.tasks.get(task, [])
        if outcome not in outcomes:
            out.append(f"expected task {task} to end {outcome}; "
                       f"{'it ended ' + ', '.join(outcomes) if outcomes else 'it never ended'}")
    missing = _in_order(expect.plan, happened.plan)
    if missing is not None:
        out.append(f"expected the shared plan {missing} (in the order "
                   f"{', '.join(expect.plan)}); it was: {', '.join(happened.plan) or 'none'}")
    said = iter(happened.said)
    for words in expect.said:
        if not any(words in sentence for sentence in said):
            out.append(f"expected the robot to say {words!r} (in order); it said: "
                       f"{' / '.join(happened.said) or 'nothing'}")
            break
    for view, label, state in expect.task_states:
        if (view, label, state) not in happened.task_states:
            out.append(f"expected {label} to be {state} in {view}'s view; it never was")
    recognized = [" ".join(r) for r in happened.recognized]
    missing = _in_order([" ".join(r) for r in expect.recognized], recognized)
    if missing is not None:
        out.append(f"expected the recognition {missing} (in order); recognized: "
                   f"{', '.join(recognized) or 'nothing'}")
    if expect.within is not None and happened.end > expect.within + 1e-9:
        out.append(f"expected the run to be over within {expect.within:g}s; "
                   f"it took {happened.end:.1f}s")
    return out

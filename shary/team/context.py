"""The Context Manager: what happened, when, by whom, over the context log.

HRI/OS (Section 3.5): "the CM keeps track of everything that occurs while the
system is running ... agents can query the CM to find out what has happened
and summaries".  The context log (:mod:`shary.log.contextlog`) already archives every
event with its time, task and agent; :class:`ContextManager` reads it back as
summaries: per agent ("what did K-10 do in the last 10 minutes?") and per
team task, over a period.  The same summary is a Python object
(:class:`Summary`), a service of the team's software agent (``QUERY`` with
``service: context``), and ``shary context LOG --agent K-10 --last 10min``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from shary.log.contextlog import LogEvent, end_time, stream_events

TASK_KINDS = ("task-ready", "task-running", "task-done", "task-failed", "task-retry",
              "task-given-up", "task-unassigned", "respawn", "assignment-expired")
"""The Task Manager's rows about a team task."""


@dataclass
class Summary:
    """What one agent (or everyone, or one team task) did over a period."""

    since: float
    until: float
    agent: str | None = None
    task: str | None = None
    counts: dict[str, int] = field(default_factory=dict)
    """Event kind -> how many."""
    tasks: list[dict[str, Any]] = field(default_factory=list)
    """Team tasks (and help requests) with who did them, when, and how they ended."""
    questions: list[dict[str, Any]] = field(default_factory=list)
    """Questions asked or answered, with the answer."""
    actions: list[dict[str, Any]] = field(default_factory=list)
    """Atomic tasks performed (start, end, status)."""
    moments: list[tuple[float, str]] = field(default_factory=list)
    """What a person would want told, in order: (time, sentence)."""

    def as_json(self) -> dict[str, Any]:
        return {"since": self.since, "until": self.until, "agent": self.agent,
                "task": self.task, "counts": self.counts, "tasks": self.tasks,
                "questions": self.questions, "actions": self.actions,
                "moments": [{"time": t, "text": s} for t, s in self.moments]}


class ContextManager:
    """Summaries over a context log (see the module's docstring)."""

    def __init__(self, path: str | Path, *, before: Callable[[], Any] | None = None):
        self.path = Path(path)
        self._before = before
        """Called before reading (the team's log commits what it holds)."""

    def end(self) -> float:
        if self._before is not None:
            self._before()
        return end_time(self.path)

    def summary(self, *, agent: str | None = None, task: str | None = None,
                last: float | None = None, since: float | None = None,
                until: float | None = None) -> Summary:
        """What happened in ``[since, until]`` (or the ``last`` seconds before the log's
        end), for one agent, one team task, or everyone."""
        end = self.end()
        until = end if until is None else until
        if last is not None:
            since = max(0.0, until - last)
        since = 0.0 if since is None else since
        summary = Summary(since, until, agent, task)
        with stream_events(self.path, since=since, until=until) as events:
            for event in _relevant(events, agent, task):
                _take(summary, event)
        return summary

    def service(self, query: dict[str, Any]) -> dict[str, Any]:
        """The ``context`` service of a software agent: a query's data -> a summary."""
        last = query.get("last")
        return self.summary(agent=query.get("agent"), task=query.get("task"),
                            last=float(last) if last is not None else None).as_json()


def _relevant(events: Iterator[LogEvent], agent: str | None,
              task: str | None) -> Iterator[LogEvent]:
    for event in events:
        if agent is not None and event.agent != agent and event.data.get("to") != agent \
                and event.data.get("asker") != agent:
            continue
        if task is not None and event.task != task and event.data.get("by") != task:
            continue
        yield event


def _take(summary: Summary, event: LogEvent) -> None:
    kind, data, time = event.kind, event.data, event.time
    summary.counts[kind] = summary.counts.get(kind, 0) + 1
    say = summary.moments.append
    if kind == "task-running":
        summary.tasks.append({"task": event.task, "agent": event.agent, "start": time,
                              "end": None, "outcome": None})
        say((time, f"{event.agent} started {event.task}"))
    elif kind in ("task-done", "task-failed"):
        outcome = "done" if kind == "task-done" else "failed"
        for entry in reversed(summary.tasks):
            if entry["task"] == event.task and entry["end"] is None:
                entry["end"], entry["outcome"] = time, outcome
                break
        else:
            summary.tasks.append({"task": event.task, "agent": event.agent, "start": None,
                                  "end": time, "outcome": outcome})
        reason = f" ({data['reason']})" if data.get("reason") else ""
        say((time, f"{event.agent} {'finished' if outcome == 'done' else 'failed'} "
                   f"{event.task}{reason}"))
    elif kind == "respawn":
        say((time, f"{data.get('by')} failed: {event.task} respawned ({data.get('reason')})"))
    elif kind == "question":
        summary.questions.append({"question": data.get("question"), "asker": event.agent,
                                  "text": data.get("text"), "asked": time, "answer": None,
                                  "by": None, "data": data.get("data")})
        say((time, f"{event.agent} asked {data.get('text')!r}"))
    elif kind == "answer":
        entry = next((q for q in summary.questions if q["question"] == data.get("question")),
                     None)
        if entry is None:
            entry = {"question": data.get("question"), "asker": data.get("asker"),
                     "text": None, "asked": None}
            summary.questions.append(entry)
        entry.update(answer=data.get("value"), by=event.agent, answered=time,
                     expired=bool(data.get("expired")))
        who = "nobody (expired)" if data.get("expired") else event.agent
        say((time, f"{who} answered {data.get('value')!r} to {data.get('asker')}"))
    elif kind == "exec-request":
        summary.actions.append({"request": data.get("request"), "atomic": data.get("atomic"),
                                "agent": event.agent, "start": time, "end": None,
                                "status": None})
    elif kind == "exec-result":
        for entry in reversed(summary.actions):
            if entry["request"] == data.get("request"):
                entry["end"], entry["status"] = time, data.get("status")
                break
    elif kind in ("associate", "release", "breakpoint", "control", "help-request", "serve"):
        say((time, _sentence(kind, event)))


def _sentence(kind: str, event: LogEvent) -> str:
    data = event.data
    if kind == "associate":
        return (f"{event.agent} associated with {data.get('requester')}"
                + (f", suspending {data['suspended']}" if data.get("suspended") else ""))
    if kind == "release":
        return f"{data.get('by')} released {event.agent}"
    if kind == "breakpoint":
        return f"{event.agent} reached a breakpoint before {data.get('before')}"
    if kind == "control":
        mode = data.get("mode")
        return (f"{data.get('by')} took control of {event.agent}" if mode == "user"
                else f"{data.get('by')} handed {event.agent} back")
    if kind == "serve":
        args = ", ".join(f"{k}={v}" for k, v in (data.get("args") or {}).items())
        return f"{event.agent} served {data.get('requester')}: {data.get('skill')}" + (
            f" ({args})" if args else "")
    return f"{event.agent} asked for help: {data.get('skill')}"

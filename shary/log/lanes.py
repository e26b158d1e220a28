"""What a context log says, as items drawn in one lane per agent (:mod:`shary.log.timeline`).

:func:`collect` pairs the log's events into :class:`Item` s: acts (a scheme
state's act, from its entry to its exit), acts sent by people (points),
actions (``exec-request`` … ``exec-result``), attention (``looksAt`` facts),
recognized human actions (``recognition``, :mod:`shary.recognition`),
and a team's rows (:mod:`shary.team`): each agent's team tasks, questions and
answers, associations and user-mode control, respawns in the task band.  The
drawing is :mod:`shary.log.timeline`'s; this module only reads.
"""

from __future__ import annotations

import json
import math
import re
import zlib
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from shary.log.contextlog import LogEvent
from shary.plans.lane import plan_task

ACT_COLOURS = {
    "ASK-TASK": "#4e79a7", "ASK-HELP": "#3f8fbf", "REALIZE-TASK": "#59a14f",
    "WAIT-ATTENTION": "#f28e2b", "END-TASK": "#b07aa1", "GIVE-UP": "#9c2f2f",
    "CANCEL-TASK": "#7f7f7f",
}
_PALETTE = ("#4f8f8a", "#b8860b", "#c0587e", "#8c6d4f", "#6b6ecf", "#637939", "#a55194")
"""For other acts, picked by a checksum of the name: stable across runs, dark under white."""
ACTION_STYLES = {  # status: (fill, stroke, text)
    "done": ("#cfe0f1", "#3b6fa0", "#1d3550"),
    "failed": ("#e15759", "#a12b2d", "#ffffff"),
    "cancelled": ("#d3d3d3", "#8c8c8c", "#4d4d4d"),
    "running": ("url(#hatch)", "#3b6fa0", "#1d3550"),
}
LOOK_COLOUR = "#8fc7c2"
TEAM_COLOURS = {"team-task": "#76b7b2", "done": "#4e9f8f", "failed": "#e15759",
                "associated": "#b07aa1", "user-mode": "#f28e2b"}
"""A team's bars: tasks (running, done, failed), associations, user-mode control."""
POINT_COLOURS = {"received": "#e15f99", "unexpected": "#ffffff", "question": "#f1ce63",
                 "answer": "#59a14f", "expired": "#bab0ac", "breakpoint": "#4e79a7"}
"""Points in the act row: acts people sent, and a team's questions and answers."""
ROUTING_KINDS = frozenset({"message", "message-lost", "message-ignored", "heard",
                           "delegation"})
"""A team's routing rows: they name managers (``tasks``, ``interaction``) or the agent
chosen, not who acted; they open no lane."""
TEAM_KINDS = frozenset({"task-running", "task-done", "task-failed", "associate", "release",
                        "control", "question", "answer", "respawn", "help-request",
                        "breakpoint"})
MAIN_ARGS = ("object", "target", "place", "to", "into", "text")

@dataclass
class Item:
    """One thing drawn in a lane: a bar (``end`` None: still going) or a point (``point``)."""

    agent: str
    row: str              # "act", "action" or "look"
    start: float
    end: float | None
    label: str
    tooltip: str
    kind: str             # its css class: act, received, unexpected, an action status, look …
    colour: str = ""
    point: bool = False
    attrs: dict[str, str] = field(default_factory=dict)
    suspended: list[tuple[float, float | None]] = field(default_factory=list)
    beside: bool = False  # the label goes beside the bar (decided when packing)


@dataclass
class TaskSpan:
    """A top-level task, from its ``task-start`` to its ``task-end``."""

    node: str
    name: str
    start: float
    end: float | None = None
    outcome: str | None = None


@dataclass
class Timeline:
    """The drawable content of a log: agents in lane order, items, top-level tasks."""

    agents: list[str]
    items: list[Item]
    tasks: list[TaskSpan]
    plans: list[Item]
    robot: str | None
    t_min: float
    t_max: float


def collect(events: Iterable[LogEvent], robot: str | None = None) -> Timeline:
    """Pair the log's events into drawable items.

    The ``act`` record carries no state name: it is the one that follows the
    ``enter`` of its state in the same task, so the last state entered per
    task is kept to pair it with its ``exit``.
    """
    seen: list[str] = []
    items: list[Item] = []
    tasks: dict[str, TaskSpan] = {}
    names: dict[str, str] = {}
    subtasks: set[str] = set()
    last_entered: dict[str, str] = {}
    open_acts: dict[tuple[str, str | None], Item] = {}
    act_nodes: dict[str, Item] = {}  # the act x task node of each act bar
    open_actions: dict[str, Item] = {}
    cancels: dict[str, str] = {}
    looks: dict[tuple[str, str], Item] = {}
    recognized: dict[str, Item] = {}  # candidate -> its bar
    plan_tasks: dict[tuple[str, str | None], Item] = {}  # (task, view) -> its open state
    received: list[tuple[LogEvent, Item]] = []
    plans: list[Item] = []
    team = _Team()
    replan: str | None = None
    first_robot: str | None = None
    times: list[float] = []

    def meet(agent: Any) -> None:
        if isinstance(agent, str) and agent and agent not in seen:
            seen.append(agent)

    for e in events:
        times.append(e.time)
        if e.kind not in ROUTING_KINDS:
            meet(e.agent)
        d = e.data
        if e.kind == "node" and d.get("parent") is not None and e.task:
            subtasks.add(e.task)
            act = open_acts.get((str(d["parent"]), d.get("scheme_state")))
            if d.get("node_kind") == "act" and act is not None:
                act_nodes[e.task] = act
        elif e.kind == "task-state" and e.task in act_nodes:
            _suspension(act_nodes[e.task], e.time, d.get("state") == "suspended")
        elif e.kind == "task-start" and e.task:
            names[e.task] = str(d.get("name", e.task))
            if first_robot is None and e.agent:
                first_robot = e.agent
            roles = d.get("roles")
            for agent in roles.values() if isinstance(roles, dict) else ():
                meet(agent)
            if e.task not in subtasks:
                tasks[e.task] = TaskSpan(e.task, names[e.task], e.time)
        elif e.kind == "task-end" and e.task:
            for key in [k for k in open_acts if k[0] == e.task]:
                _close(open_acts.pop(key), e.time, "task ended")
            if e.task in tasks:
                tasks[e.task].end = e.time
                tasks[e.task].outcome = d.get("outcome")
        elif e.kind == "enter" and e.task:
            last_entered[e.task] = str(d.get("state"))
        elif e.kind == "exit" and e.task:
            act = open_acts.pop((e.task, str(d.get("state"))), None)
            if act is not None:
                _close(act, e.time, f"left on {d['event']}" if d.get("event") else "left")
        elif e.kind == "act" and e.agent:
            state = last_entered.pop(e.task, None) if e.task else None
            item = _act_item(e, state, names.get(e.task or "", ""))
            previous = open_acts.pop((e.task or "", state), None)
            if previous is not None:
                _close(previous, e.time, "superseded")
            open_acts[(e.task or "", state)] = item
            items.append(item)
        elif e.kind == "act-received" and e.agent:
            item = _received_item(e)
            received.append((e, item))
            items.append(item)
        elif e.kind == "act-unexpected" and e.agent:
            for event, item in reversed(received):
                if (event.agent, event.data.get("act"), event.task) == (
                        e.agent, d.get("act"), e.task):
                    item.kind = "unexpected"
                    item.tooltip += "\nexpected by no task"
                    break
        elif (e.kind in ("exec-request", "person-action") and e.agent
              and isinstance(d.get("request"), str)):
            item = _action_item(e)
            open_actions[d["request"]] = item
            items.append(item)
        elif e.kind == "exec-cancel" and isinstance(d.get("request"), str):
            cancels[d["request"]] = f"cancel asked at {shown_time(e.time)} s: {d.get('reason', '')}"
        elif (e.kind in ("exec-result", "person-action-end")
              and isinstance(d.get("request"), str)):
            item = open_actions.pop(d["request"], None)
            if item is not None:
                status = str(d.get("status", "done"))
                item.kind = status if status in ACTION_STYLES else "done"
                item.attrs["data-status"] = status
                note = f"{status}" + (f": {d['reason']}" if d.get("reason") else "")
                _close(item, e.time, note)
        elif e.kind == "replan":
            replan = str(d.get("reason", ""))
        elif e.kind == "plan":
            steps = d.get("steps") if isinstance(d.get("steps"), list) else []
            label = (f"{'new plan' if replan is not None else 'plan'}: {len(steps)} "
                     f"{'step' if len(steps) == 1 else 'steps'}")
            tooltip = (f"plan for {names.get(e.task or '', e.task)} [{e.task}] at "
                       f"{shown_time(e.time)} s"
                       + (f"\nreplanned because {replan}" if replan else "")
                       + "".join(f"\n  {step}" for step in steps))
            plans.append(Item("", "plan", e.time, e.time, label, tooltip, "plan", point=True,
                              attrs={"data-task": e.task or "", "data-start": repr(e.time)}))
            replan = None
        elif e.kind in ("fact-added", "fact-removed"):
            _attention(e, looks, items)
        elif e.kind == "recognition" and isinstance(d.get("candidate"), str):
            _recognized(e, recognized, items)
        elif e.kind == "plan-task" and isinstance(d.get("name"), str):
            plan_task(e, plan_tasks, items, Item, shown_time)
        elif e.kind in TEAM_KINDS:
            team.take(e, items, plans)

    for request, item in open_actions.items():
        item.kind = "running"
        item.attrs["data-status"] = "running"
        item.tooltip += "\nstill running when the log ends"
        if request in cancels:
            item.tooltip += f"\n{cancels[request]}"
    for item in [*open_acts.values(), *looks.values(), *team.open.values(),
                 *recognized.values(), *plan_tasks.values()]:
        item.tooltip += "\nstill going when the log ends"

    robot = robot or first_robot or next(
        (i.agent for i in items if i.row == "act" and not i.point), None)
    agents = ([robot] if robot else []) + [a for a in seen if a != robot]
    agents += [a for a in dict.fromkeys(i.agent for i in items) if a not in agents]
    t_min, t_max = (min(times), max(times)) if times else (0.0, 0.0)
    return Timeline(agents, items, list(tasks.values()), plans, robot, t_min, t_max)


def _suspension(item: Item, time: float, suspended: bool) -> None:
    """An act x task node suspended (an inner act, WAIT-ATTENTION …) or going on again."""
    going = bool(item.suspended) and item.suspended[-1][1] is None
    if suspended and not going:
        item.suspended.append((time, None))
    elif not suspended and going:
        item.suspended[-1] = (item.suspended[-1][0], time)
        item.tooltip += f"\nsuspended {shown_time(item.suspended[-1][0])} – {shown_time(time)} s"


def _close(item: Item, time: float, note: str) -> None:
    _suspension(item, time, False)
    item.end = time
    item.attrs["data-end"] = repr(time)
    item.tooltip += (f"\n{shown_time(item.start)} – {shown_time(time)} s "
                     f"({shown_time(time - item.start)} s), {note}")


def _act_item(e: LogEvent, state: str | None, task_name: str) -> Item:
    act = str(e.data.get("act", "?"))
    kind = f" ({e.data['act_type']})" if e.data.get("act_type") else ""
    where = f" in state {state}" if state else ""
    tooltip = f"{e.agent}: {act}{kind} of {task_name or e.task} [{e.task}]{where}"
    label = f"{act} · {task_name}" if task_name else act
    return Item(str(e.agent), "act", e.time, None, label, tooltip, "act",
                ACT_COLOURS.get(act) or _PALETTE[zlib.crc32(act.encode()) % len(_PALETTE)],
                attrs={"data-act": act, "data-task": e.task or "", "data-start": repr(e.time)})


def _received_item(e: LogEvent) -> Item:
    act = str(e.data.get("act", "?"))
    tooltip = f"{e.agent} → {act} at {shown_time(e.time)} s" + (f" [{e.task}]" if e.task else "")
    return Item(str(e.agent), "act", e.time, e.time, act, tooltip, "received", point=True,
                attrs={"data-act": act, "data-start": repr(e.time)})


def _action_item(e: LogEvent) -> Item:
    d = e.data
    atomic = str(d.get("atomic", "?"))
    args = d.get("args") if isinstance(d.get("args"), dict) else {}
    main = next((k for k in MAIN_ARGS if k in args), next(iter(sorted(args)), None))
    label = f"{atomic} {_value(args[main])}" if main is not None else atomic
    call = ", ".join(f"{k}={_value(v)}" for k, v in args.items())
    tooltip = f"{e.agent}: {atomic}({call}) [{d['request']}, task {e.task}]"
    return Item(str(e.agent), "action", e.time, None, label, tooltip, "running",
                attrs={"data-atomic": atomic, "data-request": d["request"],
                       "data-start": repr(e.time)})


def _attention(e: LogEvent, looks: dict[tuple[str, str], Item], items: list[Item]) -> None:
    """``s looksAt o`` facts, written ``{s, p, o}`` or ``{subject, predicate, object}``."""
    d = e.data
    subject, predicate, target = (d.get(k) if k in d else d.get(long) for k, long in
                                  (("s", "subject"), ("p", "predicate"), ("o", "object")))
    if predicate != "looksAt" or not isinstance(subject, str) or not subject:
        return
    key = (subject, _value(target))
    if e.kind == "fact-removed":
        item = looks.pop(key, None)
        if item is not None:
            _close(item, e.time, "looked away")
    elif key not in looks:
        item = Item(subject, "look", e.time, None, key[1], f"{subject} looks at {key[1]}",
                    "look", LOOK_COLOUR, attrs={"data-start": repr(e.time)})
        looks[key] = item
        items.append(item)


NOBODY = "(nobody)"
"""The lane of recognized effects that no human is known to have caused."""


def _recognized(e: LogEvent, open_items: dict[str, Item], items: list[Item]) -> None:
    """A human's recognized action (``recognition`` rows of one candidate): one bar from
    *possibly started* to *possibly achieved* (or abandoned), its progressing part
    marked by ``data-progressing``; an action achieved with no start seen is a point."""
    d = e.data
    candidate, state = d["candidate"], str(d.get("state"))
    params = d.get("params") if isinstance(d.get("params"), dict) else {}
    label = " ".join([str(d.get("action", "?")),
                      *(_value(v) for v in params.values() if v is not None)])
    cause = f", {d['cause']}" if d.get("cause") else ""
    fact = f" ({d['fact']})" if d.get("fact") else ""
    line = f"possibly {state} at {shown_time(e.time)} s{cause}{fact}"
    item = open_items.get(candidate)
    if item is None:
        agent = e.agent or NOBODY
        item = Item(agent, "recognized", e.time, None, label,
                    f"{agent}: {d.get('action_class', d.get('action'))} {label} "
                    f"[{candidate}]\n{line}", f"rec-{state}", point=state == "achieved",
                    attrs={"data-candidate": candidate, "data-action": str(d.get("action")),
                           "data-start": repr(e.time), "data-state": state})
        items.append(item)
        if state in ("started", "progressing"):
            open_items[candidate] = item
        else:
            item.end = e.time
        if state == "progressing":
            item.attrs["data-progressing"] = repr(e.time)
        return
    item.label, item.kind, item.attrs["data-state"] = label, f"rec-{state}", state
    item.tooltip += f"\n{line}"
    if state == "progressing":
        item.attrs["data-progressing"] = repr(e.time)
    elif state in ("achieved", "abandoned"):
        del open_items[candidate]
        item.end = e.time
        item.attrs["data-end"] = repr(e.time)


def _value(value: Any) -> str:
    if isinstance(value, str):
        return value if value and not re.search(r"\s", value) else json.dumps(value)
    return json.dumps(value, ensure_ascii=False, separators=(",", ":"), sort_keys=True)


def shown_time(t: float) -> str:
    """Seconds as a log shows them: at most three decimals, no trailing zeros."""
    return f"{t:.3f}".rstrip("0").rstrip(".") if math.isfinite(t) else str(t)


class _Team:
    """A team's rows (:mod:`shary.team`) as items: bars of team tasks, associations and
    user mode in a ``team`` row; questions and answers as points in the act row; respawns
    in the task band."""

    def __init__(self) -> None:
        self.open: dict[tuple[str, str], Item] = {}
        self.questions: dict[str, str] = {}

    def bar(self, key: tuple[str, str], e: LogEvent, label: str, tooltip: str,
            kind: str) -> Item:
        item = Item(str(e.agent), "team", e.time, None, label, tooltip, kind,
                    TEAM_COLOURS[kind], attrs={"data-start": repr(e.time), "data-team": key[0]})
        previous = self.open.pop(key, None)
        if previous is not None:
            _close(previous, e.time, "superseded")
        self.open[key] = item
        return item

    def take(self, e: LogEvent, items: list[Item], plans: list[Item]) -> None:
        d, agent = e.data, e.agent
        if e.kind == "task-running" and agent and e.task:
            items.append(self.bar(("task", e.task), e, e.task,
                                  f"{agent}: team task {e.task}", "team-task"))
        elif e.kind in ("task-done", "task-failed") and e.task:
            item = self.open.pop(("task", e.task), None)
            if item is not None:
                outcome = "done" if e.kind == "task-done" else "failed"
                item.colour = TEAM_COLOURS[outcome]
                item.attrs["data-status"] = outcome
                _close(item, e.time, outcome + (f": {d['reason']}" if d.get("reason") else ""))
        elif e.kind == "associate" and agent:
            items.append(self.bar(("with", agent), e, f"with {d.get('requester')}",
                                  f"{agent} associated with {d.get('requester')}"
                                  + (f", {d['suspended']} suspended" if d.get("suspended")
                                     else ""), "associated"))
        elif e.kind == "release" and agent:
            item = self.open.pop(("with", agent), None)
            if item is not None:
                _close(item, e.time, f"released by {d.get('by')}")
        elif e.kind == "control" and agent and d.get("mode") == "user":
            items.append(self.bar(("control", agent), e, f"user mode: {d.get('by')}",
                                  f"{d.get('by')} drives {agent}"
                                  + (f" (task {e.task})" if e.task else ""), "user-mode"))
        elif e.kind == "control" and agent:
            item = self.open.pop(("control", agent), None)
            if item is not None:
                _close(item, e.time, f"handed back by {d.get('by')}")
        elif e.kind in ("question", "help-request", "breakpoint") and agent:
            items.append(self.point(e, agent))
        elif e.kind == "answer":
            items.append(self.answer(e))
        elif e.kind == "respawn":
            plans.append(Item("", "plan", e.time, e.time, f"respawn {e.task}",
                              f"{d.get('by')} failed at {shown_time(e.time)} s: {e.task} is "
                              f"done again ({d.get('reason')})", "respawn", point=True,
                              attrs={"data-task": e.task or "", "data-start": repr(e.time)}))

    def point(self, e: LogEvent, agent: str) -> Item:
        d = e.data
        kind = "question"
        if e.kind == "help-request":
            label = f"asks for {d.get('skill')}"
            tooltip = f"{agent} asks for help: {d.get('skill')} {_value(d.get('args') or {})}"
        elif e.kind == "breakpoint":
            kind, label = "breakpoint", f"breakpoint before {d.get('before')}"
            tooltip = (f"{agent} stops {e.task} at a breakpoint, before {d.get('before')}, "
                       "to serve a request")
        else:
            text = str(d.get("text", "?"))
            self.questions[str(d.get("question"))] = text
            data = d.get("data") if isinstance(d.get("data"), dict) else {}
            label = f"asks “{text}”" + (" [image]" if data.get("image") else "")
            tooltip = (f"{agent} asks {text!r} ({d.get('question_type')}, priority "
                       f"{d.get('priority')}, expires after {d.get('expires')} s)"
                       + "".join(f"\n{k}: {_value(v)}" for k, v in data.items()))
        return Item(agent, "act", e.time, e.time, label, tooltip, kind, point=True,
                    attrs={"data-start": repr(e.time), "data-event": e.kind,
                           "data-question": str(d.get("question", ""))})

    def answer(self, e: LogEvent) -> Item:
        d = e.data
        text = self.questions.get(str(d.get("question")), "?")
        value = _value(d.get("value")) if d.get("value") is not None else "nothing"
        if d.get("expired"):
            agent, kind, label = str(d.get("asker")), "expired", f"no answer: taken as {value}"
            tooltip = f"nobody answered {text!r} in time; fallback: {value}"
        else:
            agent, kind, label = str(e.agent), "answer", f"answers {value}"
            tooltip = f"{e.agent} answers {value} to {d.get('asker')}: {text!r}"
        return Item(agent, "act", e.time, e.time, label, tooltip, kind, point=True,
                    attrs={"data-start": repr(e.time), "data-event": e.kind,
                           "data-question": str(d.get("question"))})

"""A JAHRVIS shared plan on the console's page, folded from the plan's log rows.

:class:`PlanView` is the part of :class:`shary.console.view.View` that reads a
shared plan (:mod:`shary.plans`): the plan as the follower loaded it
(``plan-loaded``: its tasks, their agents, the human decisions and their
options), each task's state in each *view* (``plan-task``: the robot's own
belief, and its estimate of each human's, NOT_SEEN included), the decisions
taken (``plan-decision``), the plan's fate (``shared-plan``), the recognized
human actions (``recognition``), where the robot's head looks (its
``look-at`` requests) and what it says (``speech``).  Like the rest of the
view it answers each event with small changes that the page (``plan.js``)
applies in place, and rebuilds itself from nothing with :meth:`snapshot`, so a
late page and the replay's slider need no other path.

Change kinds (the first item; ``static/plan.js`` applies them):

``plan PREFIX ROOT SCHEME PROBLEM VIEWS ROWS`` a plan loaded (the first, or a
replan's; an older one stays, marked replaced), every task PLANNED in every
view; ROWS in the plan's order, each ``[TASK, LABEL, AGENT, KIND, BRANCH,
OPENS, DEPTH, DECISION]``: BRANCH is the branch the row is shown with ("" the
plan's trunk, else the task that starts it), OPENS the branch an option of a
decision starts, DEPTH its nesting; ``plan-state TASK VIEW STATE``;
``plan-chose PREFIX DECISION TASK``; ``plan-status PREFIX STATE TEXT``;
``head AGENT TARGET``; ``says AGENT TEXT``; ``recognized ID T AGENT ACTION
PARAMS STATE`` (these three once a plan is loaded: the plan's panel shows them).

The timeline gets the recognized actions (a bar from started to achieved in
the person's lane, a mark when only the effect was seen) and the NOT_SEEN
spans of each human's view, through the view's own ``item`` changes.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import Any

from shary.console.viewbase import Change, ViewBase
from shary.log.contextlog import LogEvent

SCHEME = "shared-plan-task"
"""The scheme that runs each task's states (``schemes/shared-plan-task.yaml``)."""
MAX_RECOGNIZED = 40
"""Recognitions a page is sent on joining (the newest); the log keeps them all."""
NOBODY = "(nobody)"
"""The timeline's lane for effects nobody is known to have caused."""


def _text(value: Any) -> str:
    return "" if value is None else str(value)


def _list(value: Any) -> list[Any]:
    return value if isinstance(value, list) else []


class PlanView:
    """The shared plans of one run as the page shows them (see the module)."""

    def __init__(self, view: ViewBase):
        self.view = view
        self.plans: dict[str, Change] = {}
        """prefix -> its ``plan`` change, in the order they were loaded."""
        self.status: dict[str, Change] = {}
        self.chosen: dict[tuple[str, str], Change] = {}
        self.states: dict[tuple[str, str], str] = {}
        """(task, view) -> state, for the states other than PLANNED."""
        self.labels: dict[str, str] = {}
        self.agents: dict[str, str] = {}
        """task -> its agent (``a|b`` for an AgentX)."""
        self.prefix_of: dict[str, str] = {}
        self.actions: dict[str, tuple[str, list[str | None]]] = {}
        """task -> its action's name and objects (None: an open value not resolved yet),
        what an operator's report of a human action says."""
        self.head: dict[str, Change] = {}
        self.says: dict[str, Change] = {}
        self.recognized: deque[Change] = deque(maxlen=MAX_RECOGNIZED)
        self._root_plan: dict[str, str] = {}
        """The plan's node in the task tree -> the prefix of its current plan."""
        self._candidates: dict[str, str] = {}

    def apply(self, e: LogEvent, out: list[Change]) -> None:
        handler = _HANDLERS.get(e.kind)
        if handler is not None:
            handler(self, e, out)

    def snapshot(self) -> list[Change]:
        out: list[Change] = list(self.plans.values())
        out += [["plan-state", task, view, state] for (task, view), state in self.states.items()]
        out += list(self.chosen.values())
        out += list(self.status.values())
        out += list(self.head.values()) + list(self.says.values())
        out += list(self.recognized)
        return out

    def views(self, task: str) -> list[str]:
        """The views of the plan ``task`` belongs to (the robot's first)."""
        plan = self.plans.get(self.prefix_of.get(task, ""))
        return list(plan[5]) if plan is not None else []

    # -- the plan ---------------------------------------------------------------------

    def _loaded(self, e: LogEvent, out: list[Change]) -> None:
        d = e.data
        prefix = _text(d.get("prefix")) or f"plan-{e.seq}"
        views = [_text(v) for v in _list(d.get("views")) if v]
        tasks = [t for t in _list(d.get("tasks")) if isinstance(t, dict) and t.get("id")]
        decisions = {_text(d.get("id")): d for d in _list(d.get("decisions"))
                     if isinstance(d, dict)}
        rows = plan_rows(tasks)
        for t in tasks:
            self.actions[_text(t["id"])] = (_text(t.get("name")), [
                None if o is None else _text(o) for o in _list(t.get("objects"))])
        for row in rows:
            task = row[0]
            self.labels[task], self.agents[task], self.prefix_of[task] = row[1], row[2], prefix
            decision = decisions.get(row[7])
            if decision is not None and row[5]:
                row[7] = f"{row[7]}: {_text(decision.get('agent'))} decides"
        for i, name in enumerate(views):
            self.view.agent(name, "robot" if i == 0 else "human", out)
        root = _text(e.task)
        replaced = self._root_plan.get(root)
        if replaced is not None:
            self._set_status(replaced, "replaced", f"by {prefix}", out)
        self._root_plan[root] = prefix
        change = ["plan", prefix, root, SCHEME, _text(d.get("problem")), views, rows]
        self.plans[prefix] = change
        out.append(change)

    def _task(self, e: LogEvent, out: list[Change]) -> None:
        task, who, state = _text(e.task), _text(e.agent), _text(e.data.get("state"))
        if task not in self.prefix_of or not who or not state:
            return
        key = (task, who)
        before = self.states.get(key, "PLANNED")
        self.states[key] = state
        out.append(["plan-state", task, who, state])
        label = self.labels.get(task, task)
        estimate = bool(self.views(task)) and who != self.views(task)[0]
        item = f"ns:{task}:{who}"
        if state == "NOT_SEEN":
            self.view.add_item(item, who, e.time, f"NOT_SEEN {label}", "not-seen", out)
            self.view.line(e, "plan", f"{who} did not see {label} (the robot's estimate)", out)
        elif before == "NOT_SEEN":
            self.view.end_item(item, e.time, "not-seen", out)
            how = e.data.get("reason") or e.data.get("event") or ""
            self.view.line(e, "plan", f"{who} now knows {label} is {state}"
                            + (f" ({how})" if how else ""), out)
        elif not estimate and state in ("EXECUTED", "NOT_STARTING", "NOT_FINISHED"):
            self.view.line(e, "plan", f"{label}: {state}", out)

    def _decision(self, e: LogEvent, out: list[Change]) -> None:
        task = _text(e.task)
        prefix = self.prefix_of.get(task)
        if prefix is None:
            return
        decision = _text(e.data.get("decision"))
        change = ["plan-chose", prefix, decision, task]
        self.chosen[(prefix, decision)] = change
        out.append(change)
        self.view.line(e, "plan", f"{decision}: {e.agent or '?'} chose "
                        f"{self.labels.get(task, task)}", out)

    def _shared(self, e: LogEvent, out: list[Change]) -> None:
        prefix = self._root_plan.get(_text(e.task))
        state = _text(e.data.get("state"))
        reason = _text(e.data.get("reason"))
        if prefix is not None:
            self._set_status(prefix, state, reason, out)
        problem = e.data.get("problem")
        self.view.line(e, "plan", f"shared plan{' ' + str(problem) if problem else ''}: "
                        f"{state}" + (f" ({reason})" if reason else ""), out)

    def _set_status(self, prefix: str, state: str, text: str, out: list[Change]) -> None:
        change = ["plan-status", prefix, state, text]
        self.status[prefix] = change
        out.append(change)

    def _resolved(self, e: LogEvent, out: list[Change]) -> None:
        """An AgentX's agent or a query's value chosen as its task starts."""
        task, params = _text(e.task), [_text(p) for p in _list(e.data.get("params"))]
        if task in self.actions and e.agent:
            self.agents[task] = e.agent
            objects = params[1:] if params[:1] == [e.agent] else params
            self.actions[task] = (self.actions[task][0], list(objects))

    def _match(self, e: LogEvent, out: list[Change]) -> None:
        match = _text(e.data.get("match"))
        if match in ("useful", "harmful", "reported"):
            what = self.labels.get(_text(e.task)) or _text(e.data.get("action"))
            self.view.line(e, "plan", f"{match}: {what}: {_text(e.data.get('why'))}", out)

    # -- the robot's head and voice, the people's recognized actions ----------------------

    def _request(self, e: LogEvent, out: list[Change]) -> None:
        args = e.data.get("args")
        if self.plans and e.data.get("atomic") == "look-at" and isinstance(args, dict) \
                and e.agent:
            change = ["head", e.agent, _text(args.get("target"))]
            self.head[e.agent] = change
            out.append(change)

    def _speech(self, e: LogEvent, out: list[Change]) -> None:
        if self.plans and e.agent:
            change = ["says", e.agent, _text(e.data.get("text"))]
            self.says[e.agent] = change
            out.append(change)

    def _recognition(self, e: LogEvent, out: list[Change]) -> None:
        d = e.data
        state, action = _text(d.get("state")), _text(d.get("action"))
        candidate = _text(d.get("candidate"))
        params = d.get("params")
        shown = " ".join(_text(v) for v in params.values() if v is not None) \
            if isinstance(params, dict) else ""
        who = e.agent or NOBODY
        if self.plans:  # the plan's panel lists them; any run's timeline shows them
            change = ["recognized", candidate, e.time, who, action, shown, state]
            self.recognized.append(change)
            out.append(change)
        label = f"{action} {shown}".strip()
        item = self._candidates.get(candidate)
        if state in ("started", "progressing") and item is None:
            item = self._candidates[candidate] = f"rc:{candidate}:{e.seq}"
            self.view.add_item(item, who, e.time, label, "recognized", out)
        elif state in ("achieved", "abandoned"):
            self._candidates.pop(candidate, None)
            if item is None:  # the effect alone was seen: a mark
                item = f"rc:{candidate}:{e.seq}"
                self.view.add_item(item, who, e.time, label, "recognized", out)
            self.view.end_item(item, e.time, f"recognized-{state}", out)
            if state == "achieved":
                self.view.line(e, "recognized", f"recognized: {who} {label}", out)


def plan_rows(tasks: list[dict[str, Any]]) -> list[list[Any]]:
    """The plan's tasks in the order a person reads it: each branch after the task that
    forks it, depth first (see the module's ``plan`` change for the row's fields).

    Walked with a stack, not recursion, and each task once: a log's plan may be long,
    nested or even cyclic, and the page must still get every task."""
    by_id = {_text(t["id"]): t for t in tasks}
    following: dict[str | None, list[str]] = {}
    for task_id, task in by_id.items():
        preds = [_text(p) for p in _list(task.get("after")) if _text(p) in by_id]
        for pred in preds or [None]:
            following.setdefault(pred, []).append(task_id)
    rows: list[list[Any]] = []
    seen: set[str] = set()
    # (task, the branch its row is shown with, the branch it is on, depth, heads a branch)
    stack: list[tuple[str, str, str, int, bool]] = [
        (t, "", "", 0, False) for t in reversed(following.get(None, []))]
    leftover = [t for t in reversed(by_id)]
    while stack or leftover:
        if not stack:
            stack.append((leftover.pop(), "", "", 0, False))
            continue
        task_id, shown_with, branch, depth, heads = stack.pop()
        if task_id in seen:
            continue
        seen.add(task_id)
        task = by_id[task_id]
        rows.append([task_id, _text(task.get("label")) or task_id, _text(task.get("agent")),
                     _text(task.get("kind")) or "action", shown_with,
                     branch if heads else "", depth, _text(task.get("decision"))])
        nexts = following.get(task_id, [])
        if len(nexts) == 1:
            stack.append((nexts[0], branch, branch, depth, False))
        else:
            stack.extend((n, branch, n, depth + 1, True) for n in reversed(nexts))
    return rows


_HANDLERS: dict[str, Callable[[PlanView, LogEvent, list[Any]], None]] = {
    "plan-loaded": PlanView._loaded, "plan-task": PlanView._task,
    "plan-decision": PlanView._decision, "shared-plan": PlanView._shared,
    "plan-match": PlanView._match, "plan-resolve": PlanView._resolved,
    "exec-request": PlanView._request, "speech": PlanView._speech,
    "recognition": PlanView._recognition,
}

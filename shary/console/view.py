"""What the page shows, folded from context-log events: one fold for live runs and replays.

:class:`View` reads events one at a time (:meth:`View.apply`) and answers
each with *changes*: small JSON arrays that the page applies to its DOM in
place (``["state", "n4", "done"]`` recolours one node of the task tree).  A
page that joins late, or a replay's slider, gets :meth:`View.snapshot`: the
changes that build the current view from nothing.  So the page has one code
path, and the server sends a few bytes per event instead of redrawing.

The data model is per agent, so that a team fits: ``agents`` (name, kind),
each task run with its agent, scheme and configuration (one diagram per
running task, grouped by agent on the page), the task tree, one timeline lane
per agent, the agenda, the facts per perspective, the act/action lines and the
open questions (a robot's act whose scheme waits for a person's answer).

Change kinds (the first item; the page's ``console.js`` applies them):

``agent NAME KIND``; ``task NODE AGENT NAME SCHEME ROLES``; ``config NODE
[STATES]``; ``task-end NODE OUTCOME``; ``node ID PARENT KIND NAME STATE``;
``state ID STATE``; ``cut [IDS]``; ``item ID LANE T0 LABEL CLASS``;
``item-end ID T1 CLASS``; ``goal ID NAME ARGS PRIORITY STATE``; ``fact
PERSPECTIVE S P O ADDED``; ``line T WHO KIND TEXT``; ``question NODE ACT
[AGENTS] [ANSWERS] IMAGE``; ``question-end NODE``; ``time T``; ``status {…}``;
and a team's (:mod:`shary.console.teamview`).  A shared plan's kinds (``plan``,
``plan-state`` …) are :mod:`shary.console.planview`'s.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from shary.console.planview import PlanView
from shary.console.teamview import TeamView
from shary.console.viewbase import Change, ViewBase
from shary.log.contextlog import LogEvent
from shary.statechart.acts import ACT_TYPES
from shary.statechart.model import Scheme

SchemeLookup = Callable[[str], "Scheme | None"]

GOAL_STATES = {"goal-added": "pending", "goal-started": "active", "goal-suspended": "suspended",
               "goal-resumed": "active"}
AGENT_KINDS = ("robot", "human")


class View(ViewBase):
    """The console's picture of one run, kept up to date by :meth:`apply`."""

    def __init__(self, schemes: SchemeLookup):
        super().__init__()
        self.schemes = schemes
        self.time = 0.0
        self.tasks: dict[str, dict[str, Any]] = {}
        self.nodes: dict[str, list[Any]] = {}
        self.goals: dict[int | str, list[Any]] = {}
        self.facts: dict[str, dict[tuple[str, str, str], None]] = {}
        self.questions: dict[str, Change] = {}
        self.image: str | None = None
        """The latest snapshot (a file name in the run's folder), attached to questions."""
        self._open_acts: dict[tuple[str, str], str] = {}
        self._entered: dict[str, str] = {}
        self._requests: dict[str, str] = {}
        self.team = TeamView(self)
        """A team's managers and members (:mod:`shary.console.teamview`)."""
        self.plans = PlanView(self)
        """The shared plans (JAHRVIS), folded into the same changes: :mod:`.planview`."""

    # -- folding ------------------------------------------------------------------

    def apply(self, e: LogEvent) -> list[Change]:
        """Fold one event; return what changed, as the page's changes."""
        out: list[Change] = []
        if e.time != self.time:
            self.time = e.time
            out.append(["time", e.time])
        handler = _HANDLERS.get(e.kind)
        if handler is None:
            if e.kind.startswith("goal-"):
                handler = View._goal
            elif e.kind.startswith("fact-"):
                handler = View._fact
        if handler is not None:
            handler(self, e, out)
        else:
            self.team.apply(e, out)
        self.plans.apply(e, out)
        return out

    def snapshot(self) -> list[Change]:
        """The changes that build this view on an empty page."""
        out: list[Change] = [["time", self.time]]
        out += [["agent", name, kind] for name, kind in self.agents.items()]
        for node, task in self.tasks.items():
            out.append(["task", node, task["agent"], task["name"], task["scheme"], task["roles"]])
            out.append(["config", node, list(task["config"])])
            if task["outcome"] is not None:
                out.append(["task-end", node, task["outcome"]])
        out += [["node", *n] for n in self.nodes.values()]
        for item in self.items.values():
            out.append(["item", *item[:5]])
            if item[5] is not None:
                out.append(["item-end", item[0], item[5], item[4]])
        out += [["goal", *g] for g in self.goals.values()]
        for perspective, facts in self.facts.items():
            out += [["fact", perspective, s, p, o, True] for s, p, o in facts]
        out += list(self.lines)
        out += list(self.questions.values())
        out += self.team.snapshot()
        out += self.plans.snapshot()
        return out

    # -- tasks, schemes and questions -----------------------------------------------

    def _task_start(self, e: LogEvent, out: list[Change]) -> None:
        roles = {str(k): str(v) for k, v in (e.data.get("roles") or {}).items()}
        scheme = self.schemes(str(e.data.get("scheme", "")))
        agent = e.agent or ""
        self.agent(agent, "robot", out)
        for role, who in roles.items():
            kind = scheme.roles.get(role, "agent") if scheme is not None else "agent"
            self.agent(who, kind if kind in AGENT_KINDS else "agent", out)
        self.tasks[e.task or ""] = {"agent": agent, "name": e.data.get("name", "?"),
                                    "scheme": e.data.get("scheme", "?"), "roles": roles,
                                    "config": {}, "outcome": None}
        out.append(["task", e.task, agent, e.data.get("name"), e.data.get("scheme"), roles])

    def _enter(self, e: LogEvent, out: list[Change]) -> None:
        task = self.tasks.get(e.task or "")
        if task is None:
            return
        state = str(e.data.get("state"))
        task["config"][state] = None
        self._entered[e.task or ""] = state
        out.append(["config", e.task, list(task["config"])])
        self._ask(e.task or "", task, out)

    def _exit(self, e: LogEvent, out: list[Change]) -> None:
        task = self.tasks.get(e.task or "")
        if task is None:
            return
        state = str(e.data.get("state"))
        task["config"].pop(state, None)
        out.append(["config", e.task, list(task["config"])])
        item = self._open_acts.pop((e.task or "", state), None)
        if item is not None:
            self.end_item(item, e.time, "act", out)
        self._ask(e.task or "", task, out)

    def _task_end(self, e: LogEvent, out: list[Change]) -> None:
        task = self.tasks.get(e.task or "")
        if task is None:
            return
        task["outcome"] = e.data.get("outcome", "done")
        out.append(["task-end", e.task, task["outcome"]])
        for key in [k for k in self._open_acts if k[0] == e.task]:
            self.end_item(self._open_acts.pop(key), e.time, "act", out)
        if self.questions.pop(e.task or "", None) is not None:
            out.append(["question-end", e.task])

    def _ask(self, node: str, task: dict[str, Any], out: list[Change]) -> None:
        """Open, change or close the task's question: the answers its active states
        wait for from the people in its roles (H-AGREE, H-DISAGREE, a user's act)."""
        scheme = self.schemes(task["scheme"])
        question: Change | None = None
        if scheme is not None and task["outcome"] is None:
            answers: dict[str, None] = {}
            asking = None
            for name in task["config"]:
                state = scheme.states.get(name)
                if state is None:
                    continue
                for transition in state.transitions:
                    for event in transition.events or ():
                        if _is_answer(scheme, event, state.act):
                            answers[event] = None
                            asking = asking or state.act
            people = [who for role, who in task["roles"].items()
                      if scheme.roles.get(role) == "human"]
            if answers and people:
                question = ["question", node, asking or "", people, list(answers), self.image]
        known = self.questions.get(node)
        if question is None and known is not None:
            del self.questions[node]
            out.append(["question-end", node])
        elif question is not None and question[:5] != (known or [])[:5]:
            self.questions[node] = question
            out.append(question)

    def _act(self, e: LogEvent, out: list[Change]) -> None:
        act = str(e.data.get("act"))
        node = e.task or ""
        task = self.tasks.get(node, {})
        self.agent(e.agent, "agent", out)
        self.line(e, "act", f"[{act}] {task.get('name', node)}", out)
        item = f"a{e.seq}"
        self._open_acts[(node, self._entered.get(node, ""))] = item
        self.add_item(item, e.agent or "", e.time, act, "act", out)

    def _received(self, e: LogEvent, out: list[Change]) -> None:
        act = str(e.data.get("act"))
        self.agent(e.agent, "agent", out)
        self.line(e, "received", act, out)
        item = f"r{e.seq}"
        self.add_item(item, e.agent or "", e.time, act, "received", out)
        self.end_item(item, e.time, "received", out)

    # -- actions --------------------------------------------------------------------

    def _request(self, e: LogEvent, out: list[Change]) -> None:
        atomic = str(e.data.get("atomic"))
        args = e.data.get("args") or {}
        shown = " ".join(str(v) for v in args.values()) if isinstance(args, dict) else ""
        self.line(e, "action", f"{atomic} {shown}".strip(), out)
        item = f"x{e.data.get('request')}"
        self._requests[str(e.data.get("request"))] = item
        self.add_item(item, e.agent or "", e.time, atomic, "action", out)

    def _result(self, e: LogEvent, out: list[Change]) -> None:
        status = str(e.data.get("status"))
        item = self._requests.pop(str(e.data.get("request")), None)
        if item is not None:
            self.end_item(item, e.time, status, out)
            if status != "done":
                reason = e.data.get("reason")
                self.line(e, "failed", f"{self.items[item][3]} {status}"
                           + (f": {reason}" if reason else ""), out)

    # -- the task tree ----------------------------------------------------------------

    def _node(self, e: LogEvent, out: list[Change]) -> None:
        node = [e.task, e.data.get("parent"), e.data.get("node_kind"), e.data.get("name"),
                e.data.get("state", "planned")]
        self.nodes[e.task or ""] = node
        out.append(["node", *node])

    def _node_state(self, e: LogEvent, out: list[Change]) -> None:
        node = self.nodes.get(e.task or "")
        if node is not None:
            node[4] = e.data.get("state")
            out.append(["state", e.task, node[4]])

    def _cut(self, e: LogEvent, out: list[Change]) -> None:
        nodes = [n for n in e.data.get("nodes") or () if self.nodes.pop(n, None) is not None]
        if nodes:
            out.append(["cut", nodes])

    # -- agenda, facts, talk ------------------------------------------------------------

    def _goal(self, e: LogEvent, out: list[Change]) -> None:
        goal_id = e.data.get("goal")
        if not isinstance(goal_id, int):
            return
        if self.team.active and e.agent:  # each robot of a team has its own agenda
            goal_id = f"{e.agent} #{goal_id}"
        goal = self.goals.get(goal_id)
        if goal is None:
            args = e.data.get("args") or {}
            text = ", ".join(f"{k}={v}" for k, v in args.items()) if isinstance(args, dict) else ""
            goal = self.goals[goal_id] = [goal_id, e.data.get("name"), text,
                                          e.data.get("priority", 0), "pending"]
        if e.kind == "goal-over":
            goal[4] = str(e.data.get("outcome", "done"))
        else:
            goal[4] = GOAL_STATES.get(e.kind, goal[4])
        out.append(["goal", *goal])

    def _fact(self, e: LogEvent, out: list[Change]) -> None:
        perspective = str(e.data.get("perspective", "?"))
        key = (str(e.data.get("s")), str(e.data.get("p")), str(e.data.get("o")))
        facts = self.facts.setdefault(perspective, {})
        if e.kind == "fact-added":
            facts[key] = None
            out.append(["fact", perspective, *key, True])
        elif e.kind == "fact-removed" and key in facts:
            del facts[key]
            out.append(["fact", perspective, *key, False])

    def _speech(self, e: LogEvent, out: list[Change]) -> None:
        self.line(e, "speech", f"“{e.data.get('text', '')}”", out)

    def _plan(self, e: LogEvent, out: list[Change]) -> None:
        steps = e.data.get("steps") or []
        self.line(e, "plan", "plan: " + " → ".join(map(str, steps)), out)

    def _operator(self, e: LogEvent, out: list[Change]) -> None:
        what = ", ".join(f"{k}={v}" for k, v in sorted(e.data.items()) if k != "action")
        self.line(e, "operator", f"{e.data.get('action', '?')} {what}".strip(), out)

    def _snapshot(self, e: LogEvent, out: list[Change]) -> None:
        name = e.data.get("file")
        if isinstance(name, str):
            self.image = name
            for question in self.questions.values():
                question[5] = name
                out.append(question)

    def _run_end(self, e: LogEvent, out: list[Change]) -> None:
        self.line(e, "end", "the run is over", out)


def _is_answer(scheme: Scheme, event: str, own_act: str | None) -> bool:
    """Whether a transition's event is an act a person sends (not the robot's, not
    a world event like ``done`` or a timeout)."""
    if event == own_act or event.startswith("after ") or "@" in event:
        return False
    kind = ACT_TYPES.get(event)
    if kind is not None:
        return kind.performer == "human"
    return scheme.acts.is_act_word(event) and not event.startswith("R-")


_HANDLERS: dict[str, Callable[[View, LogEvent, list[Change]], None]] = {
    "task-start": View._task_start, "enter": View._enter, "exit": View._exit,
    "task-end": View._task_end, "act": View._act, "act-received": View._received,
    "exec-request": View._request, "exec-result": View._result, "node": View._node,
    "task-state": View._node_state, "node-removed": View._cut, "speech": View._speech,
    "plan": View._plan, "operator": View._operator, "operator-refused": View._operator,
    "snapshot": View._snapshot, "run-end": View._run_end,
}

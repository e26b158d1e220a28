"""What the page shows of an HRI/OS team, folded from the team's log events.

:class:`~shary.console.view.View` folds what every run has (agents, schemes,
the task tree, the timeline, the lines); a team's log adds the rows of its
managers and members (docs/teams.md, "The context log of a team"), which
:class:`TeamView` folds into more changes of the same list, so a live team run
and its replay share one code path on the page (``static/team.js``):

``member NAME KIND {skills, services, remote, atomic}``: one block per agent
(``atomic``: a robot's atomic tasks and their parameters, what it may be
teleoperated with); ``team-task NAME {skill, state, agent, attempt,
respawns, reason}``: a row of the Task Manager's table (pending, ready,
offered, running, done, failed, respawned, given-up); ``holds AGENT TASK``:
the team task an agent holds (None: free); ``delegation T SUBJECT NEED SKILL
CHOSEN [RANKING]``: the Resource Manager's choice with its top three (score
and each criterion's value); ``tq QID {…}``: a question of the Interaction
Manager (asker, text, type, choices, priority, asked, expires at, holder,
image); ``tq-end QID {value, by, expired, t}``: its answer; ``control ROBOT
MODE BY``: control authority (system or user, and who drives); ``assoc ROBOT
REQUESTER``: an association (None: released); ``robot-break ROBOT STATE
BEFORE``: an operator's breakpoint on a robot (set, stopped before an atomic
task, cleared).  Team tasks, questions, user mode, associations, delegations
and messages are also items of the agents' timeline lanes.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any

from shary.console.viewbase import Change, ViewBase
from shary.log.contextlog import LogEvent

MAX_DELEGATIONS = 40
"""Delegations a page is sent on joining (the newest); the log keeps them all."""
MAX_ANSWERED = 60
"""Answered questions kept for the people's blocks."""
TASK_STATES = {"task-ready": "ready", "task-running": "running", "task-done": "done",
               "task-retry": "pending", "task-given-up": "given-up",
               "task-unassigned": "pending", "assignment-expired": "ready",
               "agent-lost": "ready"}
MEMBER_KINDS = ("robot", "human", "software")


class TeamView:
    """The team's part of the console's picture (see the module's docstring)."""

    def __init__(self, view: ViewBase):
        self.view = view
        self.members: dict[str, Change] = {}
        self.tasks: dict[str, dict[str, Any]] = {}
        self.holds: dict[str, str | None] = {}
        self.delegations: deque[Change] = deque(maxlen=MAX_DELEGATIONS)
        self.questions: dict[str, dict[str, Any]] = {}
        """Open questions by id (what :meth:`apply` sends as ``tq``)."""
        self.answered: deque[tuple[str, dict[str, Any], dict[str, Any]]] = deque(
            maxlen=MAX_ANSWERED)
        self.control: dict[str, list[Any]] = {}
        self.assoc: dict[str, str | None] = {}
        self.breaks: dict[str, list[Any]] = {}
        self._items: dict[str, str] = {}
        """What an open timeline item is for (team task, question, user mode …) -> its id."""

    @property
    def active(self) -> bool:
        """Whether the run is a team's (the page then shows the team's panels)."""
        return bool(self.members or self.tasks)

    # -- folding --------------------------------------------------------------------

    def apply(self, e: LogEvent, out: list[Change]) -> None:
        """Fold one event the common view does not know (most do nothing here)."""
        handler = _HANDLERS.get(e.kind)
        if handler is None and e.kind in TASK_STATES:
            handler = TeamView._task_state
        if handler is not None:
            handler(self, e, out)

    def snapshot(self) -> list[Change]:
        """The changes that build the team's part of the view on an empty page."""
        out: list[Change] = list(self.members.values())
        out += [["team-task", name, dict(task)] for name, task in self.tasks.items()]
        out += [["holds", agent, task] for agent, task in self.holds.items() if task]
        out += list(self.delegations)
        for qid, question, answer in self.answered:
            out += [["tq", qid, question], ["tq-end", qid, answer]]
        out += [["tq", qid, q] for qid, q in self.questions.items()]
        out += [["control", robot, *c] for robot, c in self.control.items()]
        out += [["assoc", robot, who] for robot, who in self.assoc.items() if who]
        out += [["robot-break", robot, *b] for robot, b in self.breaks.items()]
        return out

    # -- the members ----------------------------------------------------------------

    def _member(self, name: str, kind: str, about: dict[str, Any], out: list[Change]) -> None:
        kind = kind if kind in MEMBER_KINDS else "agent"
        known = self.members.get(name)
        about = {**(known[3] if known else {}), **about}
        change = ["member", name, kind, about]
        if change != known:
            self.members[name] = change
            self.view.agent(name, kind, out)
            out.append(change)

    def _team(self, e: LogEvent, out: list[Change]) -> None:
        """The roster a run records when it starts (:func:`shary.console.teamlive.roster`)."""
        for member in e.data.get("members") or ():
            if isinstance(member, dict) and isinstance(member.get("name"), str):
                self._member(member["name"], str(member.get("kind")),
                             {k: v for k, v in member.items() if k not in ("kind", "name")},
                             out)
        for task in e.data.get("tasks") or ():
            if isinstance(task, dict) and str(task.get("name")) not in self.tasks:
                self._set_task(str(task.get("name")), out, skill=task.get("skill"),
                               state="pending", after=task.get("after") or [])

    def _member_row(self, e: LogEvent, out: list[Change]) -> None:
        """A ``member`` row (every weld log has them): kind and skills."""
        if e.agent:
            self._member(e.agent, str(e.data.get("member_kind")),
                         {"skills": e.data.get("skills") or [],
                          "remote": bool(e.data.get("remote"))}, out)

    # -- the Task Manager ------------------------------------------------------------------

    def _set_task(self, name: str, out: list[Change], **fields: Any) -> dict[str, Any]:
        task = self.tasks.setdefault(name, {"skill": None, "state": "pending", "agent": None,
                                            "attempt": 1, "respawns": 0, "reason": None})
        task.update(fields)
        out.append(["team-task", name, dict(task)])
        return task

    def _hold(self, agent: str | None, task: str | None, out: list[Change]) -> None:
        if agent and self.holds.get(agent) != task:
            self.holds[agent] = task
            out.append(["holds", agent, task])

    def _task_state(self, e: LogEvent, out: list[Change]) -> None:
        name = e.task or ""
        state = TASK_STATES[e.kind]
        known = self.tasks.get(name, {})
        fields: dict[str, Any] = {"state": state}
        if e.kind == "task-ready":
            fields["skill"] = e.data.get("skill", known.get("skill"))
        if e.kind == "task-retry":
            fields["attempt"] = e.data.get("attempt", known.get("attempt", 1))
        if e.kind in ("task-given-up", "task-retry"):
            fields["reason"] = e.data.get("reason")
        if e.kind == "task-running":
            fields["agent"] = e.agent
            self._hold(e.agent, name, out)
            self._open(f"task:{name}", e.agent or "", e.time, name, "teamtask", out)
        elif e.kind in ("task-done", "task-given-up", "assignment-expired", "agent-lost"):
            self._hold(known.get("agent") or e.agent, None, out)
            self._close(f"task:{name}", e.time, "done" if e.kind == "task-done" else "failed",
                        out)
        if e.kind == "task-done":
            self.view.line(e, "team", f"{name} done", out)
        self._set_task(name, out, **fields)

    def _failed(self, e: LogEvent, out: list[Change]) -> None:
        name = e.task or ""
        reason = e.data.get("reason")
        self._hold(e.agent, None, out)
        self._close(f"task:{name}", e.time, "failed", out)
        self._set_task(name, out, state="failed", reason=reason)
        self.view.line(e, "failed", f"{name} failed" + (f": {reason}" if reason else ""), out)

    def _respawn(self, e: LogEvent, out: list[Change]) -> None:
        for name in e.data.get("tasks") or ():
            task = self.tasks.get(str(name), {})
            self._set_task(str(name), out, state="respawned", agent=None,
                           respawns=task.get("respawns", 0) + (name == e.task),
                           attempt=e.data.get("attempt", task.get("attempt", 1)))
        self.view.line(e, "team", f"respawns {e.task} (after {e.data.get('by')}: "
                                   f"{e.data.get('reason', '')})", out)
        self._mark(f"respawn{e.seq}", "tasks", e.time, f"respawn {e.task}", "respawn", out)

    def _delegation(self, e: LogEvent, out: list[Change]) -> None:
        ranking = [r for r in e.data.get("ranking") or () if isinstance(r, dict)]
        change = ["delegation", e.time, e.task, e.data.get("need"), e.data.get("skill"),
                  e.agent, ranking[:3]]
        self.delegations.append(change)
        out.append(change)
        if e.data.get("need") == "task" and e.task in self.tasks and e.agent:
            self._set_task(e.task, out, state="offered", agent=e.agent)
        if e.agent:
            self._mark(f"d{e.seq}", e.agent, e.time, f"← {e.task}", "delegation", out)
        if e.data.get("need") == "question" and e.task in self.questions:
            self.questions[e.task]["holder"] = e.agent
            out.append(["tq", e.task, self.questions[e.task]])

    # -- the Interaction Manager ------------------------------------------------------

    def _question(self, e: LogEvent, out: list[Change]) -> None:
        qid = str(e.data.get("question"))
        data = e.data.get("data") if isinstance(e.data.get("data"), dict) else {}
        image = data.get("image")
        expires = e.data.get("expires")
        question = {"asker": e.agent, "task": e.task, "text": e.data.get("text"),
                    "type": e.data.get("question_type", "yes-no"),
                    "choices": list(e.data.get("choices") or []),
                    "priority": e.data.get("priority", 0), "asked": e.time,
                    "expires": e.time + expires if isinstance(expires, (int, float)) else None,
                    "holder": e.data.get("to"),
                    "image": Path(image).name if isinstance(image, str) else None}
        self.questions[qid] = question
        out.append(["tq", qid, question])
        self.view.line(e, "question", f"asks {qid}: “{question['text']}”"
                        + (f" [{question['image']}]" if question["image"] else ""), out)
        self._open(f"q:{qid}", e.agent or "", e.time, f"? {qid}", "question", out)

    def _answer(self, e: LogEvent, out: list[Change]) -> None:
        qid = str(e.data.get("question"))
        question = self.questions.pop(qid, None)
        if question is None:
            return
        answer = {"value": e.data.get("value"), "by": e.agent, "t": e.time,
                  "expired": bool(e.data.get("expired"))}
        self.answered.append((qid, question, answer))
        out.append(["tq-end", qid, answer])
        said = "expired, taken as" if answer["expired"] else "answers"
        self.view.line(e, "answer", f"{said} {qid}: {answer['value']!r}", out)
        self._close(f"q:{qid}", e.time, "expired" if answer["expired"] else "answered", out)
        if e.agent:
            self._mark(f"an{e.seq}", e.agent, e.time, f"{answer['value']}", "answer", out)

    def _waiting(self, e: LogEvent, out: list[Change]) -> None:
        qid = str(e.data.get("question"))
        if qid in self.questions:
            self.questions[qid]["holder"] = None
            out.append(["tq", qid, self.questions[qid]])

    # -- robots: control authority, association, breakpoints ----------------------------

    def _control(self, e: LogEvent, out: list[Change]) -> None:
        if not e.agent:
            return
        mode, by = str(e.data.get("mode")), e.data.get("by")
        self.control[e.agent] = [mode, by]
        out.append(["control", e.agent, mode, by])
        said = f"user mode, driven by {by}" if mode == "user" else \
            f"system mode (handed back by {by})"
        self.view.line(e, "control", said, out)
        if mode == "user":
            self._open(f"user:{e.agent}", e.agent, e.time, f"driven by {by}", "usermode", out)
        else:
            self._close(f"user:{e.agent}", e.time, "usermode", out)

    def _associate(self, e: LogEvent, out: list[Change]) -> None:
        if not e.agent:
            return
        who = e.data.get("requester") if e.kind == "associate" else None
        self.assoc[e.agent] = who
        out.append(["assoc", e.agent, who])
        if who:
            self.view.line(e, "team", f"associated with {who}", out)
            self._open(f"assoc:{e.agent}", e.agent, e.time, f"with {who}", "assoc", out)
        else:
            self.view.line(e, "team", f"released by {e.data.get('by')}", out)
            self._close(f"assoc:{e.agent}", e.time, "assoc", out)

    def _robot_break(self, e: LogEvent, out: list[Change]) -> None:
        if not e.agent:
            return
        state, before = str(e.data.get("state")), e.data.get("before")
        self.breaks[e.agent] = [state, before]
        out.append(["robot-break", e.agent, state, before])
        if state == "stopped":
            self.view.line(e, "operator", f"stopped at the operator's breakpoint, before "
                                           f"{before}", out)

    # -- the site's own events ----------------------------------------------------------

    def _message(self, e: LogEvent, out: list[Change]) -> None:
        # a mark without a label: messages come in bursts, and their words would overlap
        self._mark(f"m{e.seq}", e.agent or "?", e.time, "", "message", out)

    def _site(self, e: LogEvent, out: list[Change]) -> None:
        self.view.line(e, "site", f"{e.data.get('what', '')}: {e.data.get('text', '')}", out)

    def _help(self, e: LogEvent, out: list[Change]) -> None:
        args = e.data.get("args") or {}
        shown = " ".join(f"{k}={v}" for k, v in args.items()) if isinstance(args, dict) else ""
        self.view.line(e, "team", f"asks for help: {e.data.get('skill')} {shown}".strip(), out)

    # -- timeline items ---------------------------------------------------------------

    def _open(self, key: str, lane: str, t: float, label: str, cls: str,
              out: list[Change]) -> None:
        self._close(key, t, cls, out)
        item = f"{key}@{t:.3f}"
        self._items[key] = item
        self.view.add_item(item, lane, t, label, cls, out)

    def _close(self, key: str, t: float, cls: str, out: list[Change]) -> None:
        item = self._items.pop(key, None)
        if item is not None:
            self.view.end_item(item, t, cls, out)

    def _mark(self, item: str, lane: str, t: float, label: str, cls: str,
              out: list[Change]) -> None:
        self.view.add_item(item, lane, t, label, cls, out)
        self.view.end_item(item, t, cls, out)


_HANDLERS: dict[str, Callable[[TeamView, LogEvent, list[Any]], None]] = {
    "team": TeamView._team, "member": TeamView._member_row,
    "task-failed": TeamView._failed, "respawn": TeamView._respawn,
    "delegation": TeamView._delegation, "question": TeamView._question,
    "answer": TeamView._answer, "question-waiting": TeamView._waiting,
    "control": TeamView._control, "associate": TeamView._associate,
    "release": TeamView._associate, "robot-breakpoint": TeamView._robot_break,
    "message": TeamView._message, "site": TeamView._site, "help-request": TeamView._help,
}

"""shary as a node other nodes talk to: ask for a task, send a person's act.

``~/run_task`` is a ROS 2 action of shary's own interface package
(``shary_interfaces/action/RunTask``, built from ``ros/shary_interfaces`` by
``pip install '.[ros]'``), so any node calls it with a plain action client:

goal      ``task`` (a task of the recipe library) and ``parameters`` (name, value): a
          goal naming an unknown task, or missing or adding parameters, is rejected at
          once, the reason in the node's log and the context log (``run-task`` row)
feedback  ``kind`` ``act`` (``jido: ASK``) or ``action`` (``jido navigate {…}``,
          ``jido succeeded``) as the task's acts and the robot's actions happen,
          ``node`` the task's node in the task tree, ``time`` the supervisor's clock
result    ``verdict`` and ``reason``: ``done`` (status SUCCEEDED, no reason); ``declined``
          (the person said no: ``alice said no``); ``failed`` (the cause the log holds:
          the last failed action's reason, ``node gone: …``, ``server unavailable: …``,
          the server's abort text, or the scheme's timeout, then the end state);
          ``cancelled`` (the client's cancel, or shary stopping: the reason); every
          verdict but ``done`` has status ABORTED, except a cancel the client asked
          for: CANCELED

A cancel is accepted at once and cancels the task in the engine (twice: once).  While
shary stops (:mod:`shary.ros.stop`) new goals are rejected, and each goal is answered
before the node goes.

Two topics, ``std_msgs/String`` JSON, carry what a person does and what shary does to
people (a dialogue manager, the simulated people of ``shary world --ros``):

``~/person_act``  ``{"agent": NAME, "act": ACT, "data": …, "task": NODE}``: a person's
                  act (H-AGREE …), given to the supervisor as if perceived (``task``,
                  optional: the task it answers)
``~/acts``        ``{"node": NODE, "task": NAME, "act": ACT, "agent": …, "roles": {ROLE:
                  AGENT}, "env": {PARAM: VALUE}}`` as each act of a task begins, and
                  ``{"ended": NODE}`` when a task ends

Callbacks only put events on the engine's loop; tasks start and end there
(:meth:`~shary.ros.node.RosNode.serve_goals`).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

from shary.kernel.recipes import ROBOT_PARAM
from shary.ros.node import RosNode

ACTION = "~/run_task"
SETTLE_POLL = 0.02
"""Seconds between two looks at a cancelled task's robot goals before its answer."""


class RosTaskServer:
    """``~/run_task``, ``~/person_act`` and ``~/acts`` for a supervisor (see the module's
    docstring)."""

    def __init__(self, node: RosNode, sup: Any):
        from shary_interfaces.action import RunTask
        from std_msgs.msg import String

        self.node = node
        self.sup = sup
        self._feedback = RunTask.Feedback
        self._result = RunTask.Result
        self.goals: dict[bytes, _Goal] = {}
        """Goal key -> the goal, from its start to its verdict (on the engine's loop)."""
        self._by_node: dict[str, _Goal] = {}
        self._starting: _Goal | None = None
        """The goal whose task is starting: the events told meanwhile are its own."""
        self._said_no = "the partner"
        """Who last said no (an ``act-received`` H-DISAGREE): a declined task's reason."""
        self.stopping: str | None = None
        """Why shary stops (no new goal is taken), or None."""
        self.unsettled: Callable[[], list[Any]] = list
        """The robot's goals that a server may still run (the executors')."""
        self._asked_by: dict[str, _Goal] = {}
        """Request id -> the requested task's goal whose step asked for it."""
        node.serve_goals(RunTask, ACTION, self._start, self._cancel, accept=self._accept)
        node.subscription(String, "~/person_act", lambda m: node.put(self._act, m.data))
        self.acts_pub = node.publisher(String, "~/acts", depth=100)
        sup.act_listeners.append(self._act_started)

    def _send(self, publisher: Any, data: dict[str, Any]) -> None:
        from std_msgs.msg import String

        publisher.publish(String(data=json.dumps(data)))

    # -- goals ----------------------------------------------------------------------------

    def unanswered(self) -> int:
        """Goals accepted and not yet answered."""
        return self.node.open_goals(ACTION)

    def _accept(self, goal: Any) -> str | None:
        """Why ``goal`` cannot be a task (in rclpy's goal callback: it reads only the
        recipe library), or None."""
        problem = (f"shary is stopping ({self.stopping})" if self.stopping is not None
                   else self._problem(goal.task, [p.name for p in goal.parameters]))
        if problem is not None:
            self.node.put(self._rejected, goal.task, problem)
        return problem

    def _problem(self, name: str, params: list[str]) -> str | None:
        task = self.sup.library.tasks.get(name)
        if task is None:
            return f"no task {name!r} (known: {', '.join(sorted(self.sup.library.tasks))})"
        twice = sorted({p for p in params if params.count(p) > 1})
        missing = [p for p in task.params if p not in params]
        unknown = [p for p in params if p not in task.params and p != ROBOT_PARAM]
        if twice or missing or unknown:
            return (f"task {name!r} takes {', '.join(task.params) or 'nothing'}"
                    + "".join(f"; {what}: {', '.join(names)}" for what, names in (
                        ("missing", missing), ("unknown", unknown), ("given twice", twice))
                        if names))
        return None

    def _rejected(self, name: str, reason: str) -> None:
        self.sup.record("run-task", name=name, verdict="rejected", reason=reason)

    def _start(self, key: bytes, goal: Any, end: Any) -> None:
        name, args = goal.task, {p.name: p.value for p in goal.parameters}
        if self.stopping is not None:  # accepted just before the stop began
            end(self._result(verdict="cancelled", reason=self.stopping), failed=True)
            return
        entry = self._starting = _Goal(key, end)
        try:
            run = self.sup.start_task(name, args)
        except (KeyError, ValueError, TypeError) as err:
            reason = f"{name} cannot start: {err}"
            self.sup.record("run-task", name=name, verdict="failed", reason=reason)
            end(self._result(verdict="failed", reason=reason), failed=True)
            return
        finally:
            self._starting = None
        entry.node = run.node
        self.goals[key] = self._by_node[run.node] = entry
        self.sup.record("run-task", task=run.node, name=name)
        if run.ended:  # it ended as it started
            self._ended(entry, run.outcome or "done", "its start", "")

    def _cancel(self, key: bytes) -> None:
        entry = self.goals.get(key)
        if entry is None or entry.cancel_asked:
            return
        entry.cancel_asked = True
        try:
            self.sup.cancel_task(entry.node, "cancelled by the client of ~/run_task")
        except KeyError:
            pass  # it has just ended: its verdict is on its way

    def _ended(self, entry: _Goal, outcome: str, state: str, reason: str) -> None:
        """Answer the goal: its verdict and the reason the log gave (module docstring);
        a cancelled task's once the robot's servers have answered the cancels of its
        goals (the client knows the robot has stopped when it hears)."""
        self.goals.pop(entry.key, None)
        self._by_node.pop(entry.node, None)
        if outcome == "cancelled" and self._robot_busy(entry):
            self.sup.loop.call_later(SETTLE_POLL, self._ended, entry, outcome, state, reason)
            return
        verdict = outcome
        if outcome != "cancelled" and entry.declined:
            verdict, reason = "declined", entry.declined
        elif outcome not in ("done", "cancelled"):
            verdict = "failed"
            cause = entry.failure or entry.timeout
            reason = reason or (f"{cause}; it ended in {state}" if cause
                                else f"it ended in {state}")
        reason = reason if verdict != "done" else ""
        for request in [r for r, asker in self._asked_by.items() if asker is entry]:
            del self._asked_by[request]
        self.sup.record("run-task", task=entry.node, verdict=verdict, reason=reason or None)
        entry.end(self._result(verdict=verdict, reason=reason),
                  canceled=verdict == "cancelled" and entry.cancel_asked,
                  failed=verdict != "done")

    def _robot_busy(self, entry: _Goal) -> bool:
        """Whether a robot goal of ``entry``'s task (or of its subtasks) is still unsettled
        (a cancelled task's steps are already cut from the tree: its requests are known
        from their ``exec-request`` rows)."""
        return any(self._asked_by.get(goal.request.id) is entry for goal in self.unsettled())

    # -- people -----------------------------------------------------------------------------

    def _act(self, text: str) -> None:
        act = _json(text)
        task = act.get("task")
        if isinstance(act.get("agent"), str) and isinstance(act.get("act"), str):
            self.sup.receive_act(act["agent"], act["act"], act.get("data"),
                                 task=task if isinstance(task, str) else None)

    def _act_started(self, run: Any, state: Any, agent: str) -> None:
        self._send(self.acts_pub, {"node": run.node, "task": run.type.name, "act": state.act,
                                   "agent": agent, "roles": dict(run.roles),
                                   "env": {str(k): _plain(v) for k, v in run.env.items()}})

    # -- from the supervisor's log ---------------------------------------------------------

    def listener(self, time: float, kind: str, task: str | None, agent: str | None,
                 data: dict[str, Any]) -> None:
        """Told every logged event: a requested task's feedback and verdict; a task's end
        on ``~/acts``."""
        if kind == "task-end" and task is not None:
            self._send(self.acts_pub, {"ended": task})
            entry = self._by_node.get(task)
            if entry is not None:
                self._ended(entry, str(data.get("outcome", "done")), str(data.get("state")),
                            str(data.get("reason") or ""))
                return
        if kind == "act-received" and data.get("act") == "H-DISAGREE" and agent:
            self._said_no = agent
        if task is None or not self._by_node and self._starting is None:
            return
        if kind in ("event", "exec-result", "enter"):
            self._cause(kind, task, data)
        if kind == "act":
            text = f"{agent}: {data.get('act')}"
        elif kind == "exec-request":
            asker = self._requested(task) or self._starting
            if asker is not None:
                self._asked_by[str(data.get("request"))] = asker
            text = f"{agent} {data.get('atomic')} {json.dumps(data.get('args') or {})}"
        elif kind == "exec-result":
            text = f"{agent} {data.get('status')}" + (f": {data['reason']}"
                                                      if data.get("reason") else "")
        else:
            return
        entry = self._requested(task) or self._starting
        if entry is not None:
            entry.end.feedback(self._feedback(kind="act" if kind == "act" else "action",
                                              text=text, node=task, time=float(time)))

    def _cause(self, kind: str, task: str, data: dict[str, Any]) -> None:
        """Keep what a requested task's verdict will say: who said no, the last failure,
        a timeout of its scheme."""
        entry = self._requested(task) or self._starting
        if entry is None:
            return
        if kind == "event" and data.get("event") in ("H-DISAGREE", "H-AGREE"):
            entry.declined = (f"{self._said_no} said no" if data["event"] == "H-DISAGREE"
                              else "")
        elif kind == "exec-result" and data.get("status") == "failed" and data.get("reason"):
            entry.failure = str(data["reason"])
        elif kind == "exec-result" and data.get("status") == "cancelled" and data.get("reason"):
            entry.failure = entry.failure or str(data["reason"])  # preempted, superseded
        elif kind == "enter" and str(data.get("event") or "").startswith("after "):
            entry.timeout = (f"nothing came within {str(data['event'])[6:].split('@')[0]} "
                             f"(the scheme's timeout, to {data.get('state')})")

    def _requested(self, node: str) -> _Goal | None:
        """The goal whose task is ``node`` or one of its ancestors in the task tree."""
        tree = self.sup.tree
        current: str | None = node
        while current is not None:
            entry = self._by_node.get(current)
            if entry is not None or current not in tree:
                return entry
            current = tree.parent(current)
        return None


class _Goal:
    """A goal of ``~/run_task`` whose task runs: its key, its task's node, how it ends."""

    __slots__ = ("key", "node", "end", "cancel_asked", "declined", "failure", "timeout")

    def __init__(self, key: bytes, end: Any):
        self.key, self.end = key, end
        self.node = ""
        self.cancel_asked = False
        self.declined = ""
        """Who said no, when the task's last answer was no."""
        self.failure = ""
        """The reason of the task's last failed action."""
        self.timeout = ""
        """The task's scheme's last timeout."""


def _plain(value: Any) -> Any:
    """A value as JSON carries it (a fact's object that is not a number or text: its name)."""
    return value if isinstance(value, (str, int, float, bool)) or value is None else str(value)


def _json(text: str) -> dict[str, Any]:
    try:
        value = json.loads(text)
    except ValueError:
        return {}
    return value if isinstance(value, dict) else {}

"""shary as a node other nodes talk to: ask for a task, send a person's act.

A ROS 2 *action* needs an interface package with a task's name and
parameters in its goal; none on PyPI has one (the Jazzy wheels carry only the
standard messages, and ``test_msgs``' actions carry numbers).  So
``~/run_task`` is an action protocol over ``std_msgs/String`` JSON topics,
which any ROS node (``ros2 topic pub`` too) can use:

``~/run_task/goal``      ``{"id": ID, "task": NAME, "with": {PARAM: VALUE}}``
``~/run_task/cancel``    ``{"id": ID}``
``~/run_task/feedback``  ``{"id": ID, "kind": "act"|"action", "text": …}`` as the
                         task's acts and the robot's actions happen
``~/run_task/result``    ``{"id": ID, "verdict": OUTCOME, "reason": …}``: the task's
                         outcome (``rejected`` when it cannot be started)
``~/person_act``         ``{"agent": NAME, "act": ACT, "data": …, "task": NODE}``: a
                         person's act (H-AGREE …), given to the supervisor as if
                         perceived (``task``, optional: the task it answers)
``~/acts``               ``{"node": NODE, "task": NAME, "act": ACT, "agent": …, "roles":
                         {ROLE: AGENT}, "env": {PARAM: VALUE}}`` as each act of a task
                         begins, and ``{"ended": NODE}`` when the task ends: what the
                         robot is doing with whom, for a simulated person (``shary
                         world --ros``) or a dialogue manager

The result topic is reliable with a depth of 100, so a client that subscribed
before sending its goal gets its verdict.  Callbacks put the message on the
node's inbox; starting and cancelling tasks happen on the engine's loop.
"""

from __future__ import annotations

import json
from typing import Any

from shary.ros.node import RosNode


class RosTaskServer:
    """``~/run_task`` and ``~/person_act`` for a supervisor (see the module's docstring)."""

    def __init__(self, node: RosNode, sup: Any):
        from std_msgs.msg import String

        self.node = node
        self.sup = sup
        self.runs: dict[str, Any] = {}
        """Request id -> its task run, until the verdict."""
        self._by_node: dict[str, str] = {}
        self.feedback_pub = node.publisher(String, "~/run_task/feedback", depth=100)
        self.result_pub = node.publisher(String, "~/run_task/result", depth=100)
        node.subscription(String, "~/run_task/goal", lambda m: node.put(self._goal, m.data))
        node.subscription(String, "~/run_task/cancel", lambda m: node.put(self._cancel, m.data))
        node.subscription(String, "~/person_act", lambda m: node.put(self._act, m.data))
        self.acts_pub = node.publisher(String, "~/acts", depth=100)
        sup.act_listeners.append(self._act_started)

    def _send(self, publisher: Any, data: dict[str, Any]) -> None:
        from std_msgs.msg import String

        self.node.post(publisher.publish, String(data=json.dumps(data)))

    # -- from other nodes (on the engine's loop) ------------------------------------------

    def _goal(self, text: str) -> None:
        request = _json(text)
        rid = str(request.get("id", ""))
        name, args = request.get("task"), request.get("with") or {}
        problem = None
        if not rid or not isinstance(name, str) or not isinstance(args, dict):
            problem = 'a goal is {"id": ID, "task": NAME, "with": {PARAM: VALUE}}'
        elif rid in self.runs:
            problem = f"a task with id {rid!r} is running"
        elif name not in self.sup.library.tasks:
            problem = f"no task {name!r} (known: {', '.join(sorted(self.sup.library.tasks))})"
        if problem is None:
            self.runs[rid] = None  # its first acts are feedback already
            try:
                run = self.sup.start_task(name, {str(k): v for k, v in args.items()})
            except (KeyError, ValueError, TypeError) as err:
                del self.runs[rid]
                problem = f"{name} cannot start: {err}"
        if problem is not None:
            self.sup.record("run-task", request=rid or None, verdict="rejected", reason=problem)
            self._send(self.result_pub, {"id": rid, "verdict": "rejected", "reason": problem})
            return
        self.runs[rid] = run
        self._by_node[run.node] = rid
        self.sup.record("run-task", task=run.node, request=rid, name=name)

    def _cancel(self, text: str) -> None:
        run = self.runs.get(str(_json(text).get("id", "")))
        if run is not None:
            try:
                self.sup.cancel_task(run.node, "cancelled by the client of ~/run_task")
            except KeyError:
                pass  # it has just ended: its verdict is on its way

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
        """Told every logged event: feedback while a requested task runs, its verdict;
        a task's end on ``~/acts``."""
        if kind == "task-end" and task is not None:
            self._send(self.acts_pub, {"ended": task})
        if not self.runs:
            return
        if kind == "task-end" and task in self._by_node:
            rid = self._by_node.pop(task)
            self.runs.pop(rid, None)
            outcome = str(data.get("outcome", "done"))
            self._send(self.result_pub, {"id": rid, "verdict": outcome,
                                         "reason": data.get("reason") or ""})
            return
        if kind == "act":
            text = f"{agent}: {data.get('act')}"
        elif kind == "exec-request":
            text = f"{agent} {data.get('atomic')} {json.dumps(data.get('args') or {})}"
        elif kind == "exec-result":
            text = f"{agent} {data.get('status')}" + (f": {data['reason']}"
                                                      if data.get("reason") else "")
        else:
            return
        for rid in self.runs:
            self._send(self.feedback_pub, {"id": rid, "kind": "act" if kind == "act"
                                           else "action", "text": text, "time": time})


def _plain(value: Any) -> Any:
    """A value as JSON carries it (a fact's object that is not a number or text: its name)."""
    return value if isinstance(value, (str, int, float, bool)) or value is None else str(value)


def _json(text: str) -> dict[str, Any]:
    try:
        value = json.loads(text)
    except ValueError:
        return {}
    return value if isinstance(value, dict) else {}

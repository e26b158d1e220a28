"""Executors that perform atomic tasks as ROS 2 actions, services and topics.

:class:`RosExecutors` fills shary's executor port (``start(request,
reporter)``, ``cancel(request)``) from a robot binding.  Each goal ends in one
ROS outcome, logged as a ``ros-goal`` row and given to the supervisor as done,
failed (the outcome first in the reason) or cancelled:

``succeeded``           the result is SUCCEEDED (and matches ``succeeded-if``);
``aborted``             the server aborted it, or its result says it failed;
``canceled``            the server cancelled it without being asked;
``rejected``            the server refused the goal;
``server unavailable``  no server within the ``server`` deadline (0: checked
                        once, before sending: fail fast, as BehaviorTree.ROS2);
``ack timeout``         no acceptance within the ``ack`` deadline;
``exec timeout``        no result within the ``exec`` deadline;
``invalid goal``        the goal cannot be built (a fact the robot lacks);
``node gone``           the robot's node that performs it is gone (its liveliness
                        lapsed, :mod:`shary.ros.liveliness`): a goal in flight
                        fails at once, and a new one until the node is back.

shary owns every deadline: a goal sent to an absent server hangs without an
error, and a server killed with SIGKILL still looks ready for 20 s (the DDS
lease) while its result never comes (docs/ros2.md).

A goal is sent once the parts of the robot it uses, and its action server, are free
(:mod:`shary.ros.resources`: it waits, or preempts a goal of lower priority).

Cancelling (a scheme stops or suspends the act) reports ``cancelled`` at once
and reaches the server: a goal that is running is cancelled now, one not yet
acknowledged is cancelled as soon as it is (the orphaned goals of Nav2 and
BehaviorTree.ROS2), and a goal that timed out is cancelled too.  Cancelling is
idempotent.  Whether the server confirmed is logged (``ros-cancel`` rows: the
server's answer, then ``confirmed`` or ``unconfirmed`` after the ``cancel``
deadline).  Feedback becomes ``exec-progress`` rows.

Everything runs on the supervisor's loop, whose thread also spins the node
(:class:`RosNode`): the engine calls rclpy directly, and rclpy's callbacks (a
goal's acknowledgement, result, feedback) put their events on the loop.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from shary.ros import messages
from shary.ros.binding import Binding, TaskBinding, import_interface
from shary.ros.node import RosNode
from shary.ros.qos import profile as qos_profile
from shary.ros.resources import Resources

SERVER_POLL = 0.05
"""Seconds between two looks for a server while the ``server`` deadline runs."""
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6
"""``action_msgs/GoalStatus`` codes."""


@dataclass(eq=False)
class _Goal:
    request: Any
    reporter: Any
    task: TaskBinding
    message: Any
    since: float
    phase: str = "queued"
    """``queued`` (its parts of the robot are busy), ``server``, ``ack``, ``running``,
    then ``over`` once ROS has nothing more to say."""
    handle: Any = None
    """The rclpy goal handle, once acknowledged."""
    timer: Any = None
    reported: bool = False
    cancel_wanted: bool = False
    cancel_sent: bool = False
    unconfirmed: bool = False
    """Cancelled, and its server did not end it within the ``cancel`` deadline."""
    needs: tuple[str, ...] = ()
    """The parts of the robot it holds while it runs (:mod:`shary.ros.resources`)."""


class RosExecutors:
    """The robot's atomic tasks on the interfaces of a binding (see the module's docstring)."""

    def __init__(self, node: RosNode, binding: Binding, loop: Any, *,
                 record: Callable[..., Any] | None = None,
                 fact: Callable[[str, str], Any] | None = None):
        self.node = node
        self.binding = binding
        self.loop = loop
        self.record = record or (lambda *args, **data: None)
        self.fact = fact
        """``fact(subject, predicate)``: what goals' ``{fact:…}`` templates read."""
        self._entities: dict[str, Any] = {}
        self._types: dict[str, Any] = {}
        self._goals: dict[str, _Goal] = {}
        self.gone: dict[str, str] = {}
        """Atomic tasks whose node is gone, and why (:meth:`node_gone`)."""
        self.resources = Resources(self._send, self._preempted, self.record)
        self.stopping: str | None = None
        """Why no goal is sent any more (:meth:`stop`), or None."""
        shared: dict[tuple[str, str, str], Any] = {}
        """One client per interface: atomic tasks bound to the same action share it (each
        client hears every status and feedback message of its action)."""
        for atomic, task in binding.tasks.items():
            cls = import_interface(task.type)
            if cls is None:
                continue  # a type not installed here: start() says so
            self._types[atomic] = cls
            key = (task.kind, task.name, task.type)
            if key not in shared:
                if task.kind == "action":
                    shared[key] = node.action_client(cls, task.name)
                elif task.kind == "service":
                    shared[key] = node.service_client(cls, task.name)
                else:
                    shared[key] = node.publisher(cls, task.name, qos=None if task.qos is None
                                                 else qos_profile(task.qos, None))
            self._entities[atomic] = shared[key]

    def register(self, registry: Any) -> None:
        """Fill ``registry`` (an :class:`~shary.kernel.executors.ExecutorRegistry`) with these."""
        for atomic in self.binding.tasks:
            registry.register(atomic, self)

    def ready(self) -> bool:
        """Whether every bound action and service has its server (for waiting on a robot
        before starting)."""
        return all(self.binding.tasks[atomic].kind == "topic"
                   or (entity.server_is_ready() if self.binding.tasks[atomic].kind == "action"
                       else entity.service_is_ready())
                   for atomic, entity in self._entities.items())

    # -- the executor port -------------------------------------------------------------

    def start(self, request: Any, reporter: Any) -> None:
        task = self.binding.tasks.get(request.atomic)
        if request.agent != self.binding.robot or task is None:
            reporter.failed(request, f"the binding {self.binding.name} has no "
                            f"{request.atomic} for {request.agent}")
            return
        if request.atomic not in self._types:
            reporter.failed(request, f"server unavailable: {task.type} is not installed here")
            return
        if self.stopping is not None:
            reporter.failed(request, f"not sent: {self.stopping}")
            return
        if request.atomic in self.gone:
            goal = _Goal(request, reporter, task, None, self.loop.now(), phase="over")
            self._end(goal, "failed", "node gone", self.gone[request.atomic])
            return
        cls = self._types[request.atomic]
        part = {"action": "Goal", "service": "Request"}.get(task.kind)
        try:
            message = messages.build(getattr(cls, part) if part else cls, task.goal,
                                     request.args, codes=self.binding.codes, fact=self.fact)
        except (messages.TemplateError, ValueError, TypeError, AssertionError) as err:
            reporter.failed(request, f"invalid goal: {err}")
            return
        goal = _Goal(request, reporter, task, message, self.loop.now())
        if request.atomic == "speak":  # what the robot says, as in a simulated run's log
            self.record("speech", agent=request.agent, text=str(request.args.get("text", "")),
                        request=request.id)
        if task.kind == "topic":
            self._entities[request.atomic].publish(message)
            self._end(goal, "done", "succeeded", f"published on {task.name}")
            return
        goal.needs = (*task.resources, f"{task.kind} {task.name}") if task.kind == "action" \
            else task.resources
        self._goals[request.id] = goal
        self.resources.admit(goal)

    def cancel(self, request: Any, detail: str = "") -> None:
        """Cancel the goal of ``request`` at its server (``detail``: why, told to the
        supervisor; a cancel by default)."""
        goal = self._goals.get(request.id)
        if goal is None or goal.reported:
            return  # idempotent: an ended or cancelled goal stays as it is
        goal.cancel_wanted = True
        if goal.phase == "queued":
            goal.phase = "over"
            self._forget(goal)
            detail = detail or "cancelled before it was sent (it waited for " \
                f"{', '.join(goal.needs)})"
        elif goal.task.kind == "service":
            self._stop_timer(goal)
            goal.phase = "over"  # its answer, should it come, is ignored
            self._forget(goal)
            detail = detail or "cancelled; a service call cannot be stopped: its answer is " \
                "ignored"
        elif goal.phase == "running" and goal.handle is not None:
            self._send_cancel(goal)
            detail = detail or f"cancelled; the cancel is sent to {goal.task.name}"
        elif goal.phase in ("ack", "running"):  # cancelled once acknowledged (_acknowledged)
            detail = detail or f"cancelled; the cancel reaches {goal.task.name} once it " \
                "acknowledges"
        else:  # its server was missing: looked for again later, or never
            self._stop_timer(goal)
            goal.phase = "over"
            self._forget(goal)
            detail = detail or "cancelled before the goal was acknowledged"
        self._end(goal, "cancelled", "canceled", detail)

    def _preempted(self, goal: _Goal, reason: str) -> None:
        self.cancel(goal.request, reason)

    # -- stopping ----------------------------------------------------------------------

    def stop(self, reason: str) -> None:
        """Send no goal any more and cancel every goal in flight, each told ``cancelled``
        with ``reason`` (what is left to wait for: :meth:`unsettled`)."""
        self.stopping = reason
        for goal in list(self._goals.values()):
            self.cancel(goal.request, reason)

    def unsettled(self) -> list[Any]:
        """The goals a server may still be running: neither over (their result came) nor
        given up (a cancel unanswered past its deadline)."""
        return [goal for goal in self._goals.values()
                if goal.phase != "over" and not goal.unconfirmed]

    @staticmethod
    def describe(goal: Any) -> str:
        """A goal as a person reads it in what a stop left behind."""
        return f"{goal.request.atomic} on {goal.task.name} ({goal.request.id})"

    def node_gone(self, tasks: tuple[str, ...], reason: str) -> None:
        """The node that performs ``tasks`` is gone: their goals in flight fail now (its
        results will never come), and new ones at once until :meth:`node_back`."""
        for atomic in tasks:
            self.gone[atomic] = reason
        for goal in list(self._goals.values()):
            if goal.request.atomic in tasks:  # its result will never come, nor a cancel's
                self._stop_timer(goal)
                goal.cancel_wanted = True  # should it be acknowledged after all
                goal.phase = "over"
                self._forget(goal)
                self._end(goal, "failed", "node gone", reason)

    def node_back(self, tasks: tuple[str, ...]) -> None:
        """The node that performs ``tasks`` is there again."""
        for atomic in tasks:
            self.gone.pop(atomic, None)

    # -- phases (on the supervisor's loop) -------------------------------------------------

    def _send(self, goal: _Goal) -> None:
        """Its parts of the robot are its: send it (its ``server`` deadline runs from now)."""
        goal.since = self.loop.now()
        goal.phase = "server"
        self._try_send(goal)

    def _try_send(self, goal: _Goal) -> None:
        """Send the goal if its server is there; rclpy's callbacks put its answers on the
        loop (the acknowledgement, then on acceptance the result, and feedback)."""
        entity = self._entities[goal.request.atomic]
        node, kind = self.node, goal.task.kind
        if not (entity.server_is_ready() if kind == "action" else entity.service_is_ready()):
            self._server_missing(goal)
            return
        # the deadline of the next phase runs from the send
        if kind == "service":
            goal.phase = "running"
            goal.timer = self.loop.call_later(goal.task.deadlines["exec"], self._exec_timeout,
                                              goal)
            future = entity.call_async(goal.message)
            future.add_done_callback(lambda f: node.put(self._responded, goal, f.result()))
            return
        goal.phase = "ack"
        goal.timer = self.loop.call_later(goal.task.deadlines["ack"], self._ack_timeout, goal)

        def acknowledged(future: Any) -> None:
            handle = future.result()
            node.put(self._acknowledged, goal, handle)
            if handle.accepted:
                handle.get_result_async().add_done_callback(
                    lambda f: node.put(self._result, goal, f.result()))

        entity.send_goal_async(
            goal.message, feedback_callback=lambda f: node.put(self._feedback, goal,
                                                               f.feedback)
        ).add_done_callback(acknowledged)

    def _server_missing(self, goal: _Goal) -> None:
        waited = self.loop.now() - goal.since
        if waited + SERVER_POLL <= goal.task.deadlines["server"]:
            goal.timer = self.loop.call_later(SERVER_POLL, self._try_send, goal)
            return
        goal.phase = "over"
        self._forget(goal)
        self._end(goal, "failed", "server unavailable",
                  f"no {goal.task.kind} server {goal.task.name} "
                  + (f"within {goal.task.deadlines['server']:g} s"
                     if goal.task.deadlines["server"] > 0 else "(checked before sending)"))

    def _acknowledged(self, goal: _Goal, handle: Any) -> None:
        self._stop_timer(goal)
        goal.handle = handle
        if not handle.accepted:
            goal.phase = "over"
            self._forget(goal)
            self._end(goal, "failed", "rejected", f"{goal.task.name} rejected the goal")
            return
        goal.phase = "running"
        if goal.cancel_wanted:  # cancelled or timed out before the acknowledgement
            self.record("ros-cancel", task=goal.request.node, agent=goal.request.agent,
                        request=goal.request.id, action=goal.task.name,
                        state="sent after the acknowledgement")
            self._send_cancel(goal)
            return
        goal.timer = self.loop.call_later(goal.task.deadlines["exec"], self._exec_timeout, goal)

    def _feedback(self, goal: _Goal, feedback: Any) -> None:
        if goal.reported or not goal.task.feedback:
            return
        self.record("exec-progress", task=goal.request.node, agent=goal.request.agent,
                    request=goal.request.id, text=messages.text(goal.task.feedback, feedback))

    def _result(self, goal: _Goal, wrapped: Any) -> None:
        self._stop_timer(goal)
        goal.phase = "over"
        self._forget(goal)
        status, result = wrapped.status, wrapped.result
        if goal.reported:  # cancelled or timed out earlier: say how it ended at the server
            if goal.cancel_sent:
                self.record("ros-cancel", task=goal.request.node, agent=goal.request.agent,
                            request=goal.request.id, action=goal.task.name,
                            state="confirmed" if status == CANCELED else f"ended {status}")
            return
        self._judge(goal, status, result)

    def _responded(self, goal: _Goal, response: Any) -> None:
        self._stop_timer(goal)
        goal.phase = "over"
        self._forget(goal)
        if not goal.reported:
            self._judge(goal, SUCCEEDED, response)

    def _judge(self, goal: _Goal, status: int, result: Any) -> None:
        task = goal.task
        why = messages.text(task.reason, result) if task.reason else ""
        if status == SUCCEEDED:
            wrong = messages.matches(result, task.succeeded_if)
            if not wrong:
                self._end(goal, "done", "succeeded", "")
            else:
                self._end(goal, "failed", "aborted", why or f"{task.name} answered "
                          f"{', '.join(wrong)}")
        elif status == ABORTED:
            self._end(goal, "failed", "aborted", why or f"{task.name} aborted the goal")
        elif status == CANCELED:
            self._end(goal, "failed", "canceled", f"{task.name} cancelled the goal")
        else:
            self._end(goal, "failed", "aborted", f"{task.name} ended the goal with status "
                      f"{status}")

    def _ack_timeout(self, goal: _Goal) -> None:
        goal.timer = None
        if goal.phase != "ack":
            return
        goal.cancel_wanted = True  # should it be accepted after all, it is cancelled then
        if not goal.reported:
            self._end(goal, "failed", "ack timeout", f"{goal.task.name} did not acknowledge "
                      f"the goal within {goal.task.deadlines['ack']:g} s")
        # its parts are given up once the cancel's time is over too
        goal.timer = self.loop.call_later(goal.task.deadlines["cancel"], self._unconfirmed, goal)

    def _exec_timeout(self, goal: _Goal) -> None:
        goal.timer = None
        if goal.reported or goal.phase != "running":
            return
        if goal.task.kind == "action":
            self._send_cancel(goal)
        self._end(goal, "failed", "exec timeout", f"no result from {goal.task.name} within "
                  f"{goal.task.deadlines['exec']:g} s")

    def _send_cancel(self, goal: _Goal) -> None:
        if goal.cancel_sent:
            return
        goal.cancel_sent = True
        self._stop_timer(goal)

        if goal.handle is not None:
            goal.handle.cancel_goal_async().add_done_callback(
                lambda f: self.node.put(self._cancel_answered, goal, f.result()))
        goal.timer = self.loop.call_later(goal.task.deadlines["cancel"], self._unconfirmed, goal)

    def _cancel_answered(self, goal: _Goal, response: Any) -> None:
        self.record("ros-cancel", task=goal.request.node, agent=goal.request.agent,
                    request=goal.request.id, action=goal.task.name,
                    state="accepted" if response.goals_canceling else
                    f"refused (code {response.return_code})")

    def _unconfirmed(self, goal: _Goal) -> None:
        goal.timer = None
        if goal.phase != "over":
            goal.unconfirmed = True
            self.record("ros-cancel", task=goal.request.node, agent=goal.request.agent,
                        request=goal.request.id, action=goal.task.name,
                        state="unconfirmed" if goal.phase == "running"
                        else "unconfirmed: never acknowledged")
            self.resources.release(goal)

    # -- bookkeeping ---------------------------------------------------------------------

    def _end(self, goal: _Goal, status: str, outcome: str, detail: str) -> None:
        """Report the goal's one outcome (later news of it is only logged)."""
        if goal.reported:
            return
        goal.reported = True
        request, reporter = goal.request, goal.reporter
        reason = f"{outcome}: {detail}" if detail and status == "failed" else detail
        self.record("ros-goal", task=request.node, agent=request.agent, request=request.id,
                    interface=goal.task.name, outcome=outcome, reason=reason or None)
        if status == "done":
            reporter.done(request)
        elif status == "failed":
            reporter.failed(request, reason)
        else:
            reporter.cancelled(request, detail)

    def _stop_timer(self, goal: _Goal) -> None:
        if goal.timer is not None:
            goal.timer.cancel()
            goal.timer = None

    def _forget(self, goal: _Goal) -> None:
        """A goal over at its server: forgotten, its parts of the robot freed."""
        if goal.phase == "over" and self._goals.get(goal.request.id) is goal:
            del self._goals[goal.request.id]
            self.resources.withdraw(goal)
            self.resources.release(goal)

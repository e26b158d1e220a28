"""The one ROS 2 node of a shary process, spun by the engine's own loop.

There is no ROS thread.  The node's ``SingleThreadedExecutor`` is the waiter of
the engine's :class:`~shary.kernel.loop.EventLoop` (:meth:`RosNode.attach`): between
two timers the loop waits in rcl's wait set (:meth:`RosNode.wait`, one
``spin_once`` with the time to the next timer as its timeout), so every ROS
callback (a drained subscription, an action client's answers, a served goal,
a QoS event) runs on the engine's thread and only puts its event on the
loop's ready queue (:meth:`RosNode.put`, run once the callback has returned);
and the engine acts on ROS by calling rclpy directly (publish, send a goal,
cancel it).  Another thread (a console, a signal handler) still wakes the
loop: :meth:`RosNode.wake` gives the executor a task (``create_task``, its
thread-safe entry), which ends the wait.

Why no thread.  The node first spun in an executor thread of its own, the
engine's loop sleeping on a ``threading.Event`` that each ROS callback set.
Topic messages into facts met 6,000 a second but missed the goal of p99 <= 5 ms
to the fact in most runs (6-86 ms) while a bare rclpy subscriber draining in
its own callback kept 0.6-1.0 ms: measured stage by stage, the tail was the
hand-over between the two threads (the kernel's run queue and the GIL), not
the engine's work (docs/benchmarks.md).  With one thread there is no hand-over:
in twelve runs interleaved with the threaded node (loads 4-12), the median
p99 to the fact went from 10.4 to 5.1 ms and the p50 fell too (what is left
is the kernel's run queue); the cancel reaches the server as fast, and a
goal's round trip is a little shorter.  The price: while the
loop is busy nothing takes messages, so the DDS history (a subscription's
depth) is the only buffer.  Goals are sent and answered on the thread that
spins the executor, so the Jazzy wheel's action-client race between threads
(rclpy#1123) cannot happen.  ``EventsExecutor`` is not used (it deadlocked
here).

Shutdown is ordered as rclpy needs it: what must happen while the node still spins
first (:attr:`RosNode.before_close`: a supervisor's safe stop, :mod:`shary.ros.stop`),
then action clients and servers destroyed
(``destroy_node`` does not destroy them), then the node, the executor stopped
and the context shut down; the loop gets its default waiter back.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from shary.kernel.loop import EventWaiter
from shary.ros.env import keep_on_host

BATCH = 500
"""Most messages a drained subscription hands over at once: the loop goes back to its
timers and the node's other entities (a goal's answer) at least this often."""
LONGEST_WAIT = 0.1
"""Seconds one wait in rcl's wait set lasts at most: a signal (Ctrl-C) does not end it,
so the loop comes round this often to let Python raise it."""
SERVED_GOALS = 1000
"""Goal, result and cancel requests a served action keeps while the loop works (rclpy's
default, 10, loses the eleventh of goals sent at once)."""
NEARER = 0.001
"""Seconds by which a wait must end sooner than the one before for the executor to be
woken and begin again (:meth:`RosNode.wait`): less is the clocks' jitter."""


class RosNode:
    """One node whose executor the engine's loop spins (see the module's docstring)."""

    def __init__(self, name: str = "shary", *, domain_id: int | None = None,
                 namespace: str | None = None, use_sim_time: bool = False):
        """``use_sim_time``: the node's clock follows ``/clock`` (the ROS parameter of that
        name; :class:`~shary.ros.clock.RosClock` makes it the engine's)."""
        keep_on_host()
        import rclpy
        from rclpy.executors import SingleThreadedExecutor, TimeoutObject
        from rclpy.parameter import Parameter

        self._rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node(
            name, context=self.context, namespace=namespace,
            parameter_overrides=[Parameter("use_sim_time", value=True)] if use_sim_time
            else [])
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.waitables: list[Any] = []
        """Action clients and servers, destroyed before the node (rclpy does not)."""
        self._loop: Any = None
        self._closed = False
        self._timeout = TimeoutObject(0.0)
        """One object for every wait: rclpy keeps its generator of ready callbacks while
        the arguments of ``spin_once`` are the same (one wait set for all that is ready at
        once), and reads the timeout from it when it makes the next one."""
        self._armed = 0.0
        """When the previous wait was to end (``time.monotonic``)."""
        self._open: dict[str, int] = {}
        """Goals of each served action accepted and not yet answered (:meth:`serve_goals`)."""
        self.before_close: list[Callable[[], Any]] = []
        """Called first when the node closes, while it still spins (a safe stop)."""

    # -- the engine's loop waits here -------------------------------------------------

    def attach(self, loop: Any) -> None:
        """Make this node the waiter of ``loop`` (an :class:`~shary.kernel.loop.EventLoop`):
        its ROS callbacks run when the loop waits, and put their events on it."""
        self._loop = loop
        loop.waiter = self

    def wait(self, timeout: float) -> None:
        """Wait in rcl's wait set up to ``timeout`` seconds and run one ROS callback that
        is ready (the loop's waiter; on the loop's thread only).

        rclpy's executor yields the tasks it has pending (a served goal awaiting its end)
        before it waits, one per ``spin_once``, and then waits with the timeout it was
        given when it began: should the loop's next timer have come nearer since, the
        executor is woken so that it begins again with the new timeout."""
        timeout = min(timeout, LONGEST_WAIT)
        deadline = time.monotonic() + timeout
        if deadline < self._armed - NEARER:
            self.executor.wake()
        self._armed = deadline
        self._timeout.timeout = timeout
        self.executor.spin_once(self._timeout)

    def wake(self) -> None:
        """From any thread: end the current or the next :meth:`wait` now."""
        if not self._closed:
            self.executor.create_task(_nothing)

    def spin_for(self, seconds: float) -> None:
        """Run the node's callbacks for ``seconds`` (a world stepped by the wall clock
        between its steps; a supervisor's loop waits with :meth:`wait` instead)."""
        end = time.monotonic() + seconds
        while (left := end - time.monotonic()) > 0:
            self.wait(left)

    def put(self, handler: Callable[..., Any], *args: Any) -> None:
        """From a ROS callback: have ``handler(*args)`` run on the engine's loop once the
        callback has returned (after the work already there)."""
        self._loop.call_soon(handler, *args)

    # -- entities ---------------------------------------------------------------------

    def action_client(self, cls: Any, name: str) -> Any:
        from rclpy.action import ActionClient

        client = ActionClient(self.node, cls, name)
        self.waitables.append(client)
        return client

    def action_server(self, cls: Any, name: str, **callbacks: Any) -> Any:
        from rclpy.action import ActionServer

        server = ActionServer(self.node, cls, name, **callbacks)
        self.waitables.append(server)
        return server

    def serve_goals(self, cls: Any, name: str, start: Callable[..., Any],
                    cancel: Callable[[bytes], Any], *,
                    accept: Callable[[Any], str | None] | None = None) -> Any:
        """Serve action ``name`` whose goals are performed on the engine's side: each
        accepted goal puts ``start(key, goal, end)`` on the loop, ``end`` a
        :class:`ServedGoal` (call it to end the goal; ``end.feedback`` publishes
        feedback); a cancel request is accepted at once and puts ``cancel(key)`` (after
        ``start``, should it come before the goal runs).  ``accept(goal)`` answers at
        once: a reason to reject the goal (logged), or None.  The execute callback is a
        task of the executor that awaits its end, so no goal holds the thread (the shared
        robot, ``shary world --ros``; ``~/run_task``)."""
        from rclpy.action import CancelResponse, GoalResponse

        live: dict[bytes, Any] = {}
        logger = self.node.get_logger()
        self._open[name] = 0

        def on_goal(goal: Any) -> Any:
            reason = accept(goal) if accept is not None else None
            if reason is None:
                self._open[name] += 1
                return GoalResponse.ACCEPT
            logger.warning(f"{name}: goal rejected: {reason}")
            return GoalResponse.REJECT

        async def execute(handle: Any) -> Any:
            key = bytes(handle.goal_id.uuid)
            end = live[key] = ServedGoal(self, handle)
            self.put(start, key, handle.request, end)
            if handle.is_cancel_requested:  # asked before it ran: on_cancel did not pass it
                self.put(cancel, key)
            result, status = await end.future
            del live[key]
            if status == "canceled" and handle.is_cancel_requested:
                handle.canceled()
            elif status == "succeeded":
                handle.succeed()
            else:
                handle.abort()
            self._open[name] -= 1
            return result

        def on_cancel(handle: Any) -> Any:
            key = bytes(handle.goal_id.uuid)
            if key in live:
                self.put(cancel, key)
            return CancelResponse.ACCEPT

        from rclpy.qos import QoSProfile

        # rclpy's services keep 10 requests: more goals sent at once than that, while the
        # loop works, would be lost without an answer
        deep = QoSProfile(depth=SERVED_GOALS)
        return self.action_server(cls, name, execute_callback=execute,
                                  goal_callback=on_goal, cancel_callback=on_cancel,
                                  goal_service_qos_profile=deep,
                                  result_service_qos_profile=deep,
                                  cancel_service_qos_profile=deep)

    def open_goals(self, name: str) -> int:
        """Goals of action ``name`` (served with :meth:`serve_goals`) accepted and not yet
        answered."""
        return self._open.get(name, 0)

    def service_client(self, cls: Any, name: str) -> Any:
        return self.node.create_client(cls, name)

    def publisher(self, cls: Any, topic: str, *, latched: bool = False, depth: int = 10,
                  lease: float | None = None, qos: Any = None) -> Any:
        """A publisher; ``latched``: a late subscriber gets the last message; ``lease``:
        it offers a liveliness lease of that many seconds, asserted as long as this
        process runs (how a supervisor notices it gone: :mod:`shary.ros.liveliness`);
        ``qos``: this ``QoSProfile`` instead (a binding's, :mod:`shary.ros.qos`)."""
        from rclpy.duration import Duration
        from rclpy.qos import DurabilityPolicy, LivelinessPolicy, QoSProfile

        if qos is not None:
            return self.node.create_publisher(cls, topic, qos)
        qos = QoSProfile(depth=1 if latched else depth)
        if latched:
            qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
        if lease is not None:
            qos.liveliness = LivelinessPolicy.AUTOMATIC
            qos.liveliness_lease_duration = Duration(seconds=lease)
        return self.node.create_publisher(cls, topic, qos)

    def subscription(self, cls: Any, topic: str, callback: Callable[[Any], Any], *,
                     depth: int = 100) -> Any:
        """A subscription whose callback runs while the loop waits (it must only
        :meth:`put` events)."""
        return self.node.create_subscription(cls, topic, callback, depth)

    def drained_subscription(self, cls: Any, topic: str,
                             callback: Callable[[list[Any]], Any], *, depth: int = 1000,
                             batch: int = BATCH, qos: Any = None, events: Any = None) -> Any:
        """A subscription whose callback gets every message waiting (up to ``batch``) in
        one list, while the loop waits (it must only :meth:`put` events): for a topic
        that may carry thousands of messages a second (perception).

        rclpy's executor takes one message each time it wakes, and each wake rebuilds its
        wait set in Python over every entity of the node: 3,000-5,000 messages a second
        here, whatever the callback does (docs/benchmarks.md).  Taking the messages that
        wait with the subscription's own ``take_message``, as soon as the first is
        handed over, costs one wake and one event on the engine's loop per burst.
        ``qos`` (a ``QoSProfile``) replaces the reliable history of ``depth``; ``events``
        are rclpy's ``SubscriptionEventCallbacks`` (an incompatible publisher:
        :mod:`shary.ros.qos`)."""
        subscription: Any = None

        def drain(first: Any) -> None:
            taken = [first]
            handle = subscription.handle
            with handle:  # the handle is not destroyed while it is used
                while len(taken) < batch:
                    got = handle.take_message(cls, False)
                    if got is None:
                        break
                    taken.append(got[0])
            callback(taken)

        subscription = self.node.create_subscription(
            cls, topic, drain, qos if qos is not None else depth, event_callbacks=events)
        return subscription

    # -- shutdown -----------------------------------------------------------------------

    def close(self, timeout: float = 5.0) -> None:
        """Destroy everything, in rclpy's order (idempotent); the loop it was attached to
        sleeps on its default waiter again."""
        if self._closed:
            return
        hooks, self.before_close = self.before_close, []
        try:
            for hook in hooks:
                hook()
        finally:
            self._closed = True
            if self._loop is not None and self._loop.waiter is self:
                self._loop.waiter = EventWaiter()
            try:
                for waitable in self.waitables:
                    waitable.destroy()
                self.node.destroy_node()
            finally:
                self.executor.shutdown(timeout_sec=timeout)
                self._rclpy.try_shutdown(context=self.context)

    def __enter__(self) -> RosNode:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class ServedGoal:
    """How the engine ends a goal of :meth:`RosNode.serve_goals` and tells its progress."""

    def __init__(self, node: RosNode, handle: Any):
        from rclpy.task import Future

        self._node, self._handle = node, handle
        self.future = Future()
        """Done with ``(result, status)`` when the goal ends (awaited by the server)."""

    def __call__(self, result: Any, canceled: bool = False, failed: bool = False) -> None:
        """End the goal with ``result``: CANCELED if ``canceled`` and a client asked for
        it, ABORTED if ``failed`` (or cancelled unasked), else SUCCEEDED."""
        if self.future.done():
            return
        status = "canceled" if canceled else "aborted" if failed else "succeeded"
        self.future.set_result((result, status))
        # the executor resumes the goal's task when it next begins a wait: now
        self._node.executor.wake()

    def feedback(self, message: Any) -> None:
        """Publish ``message`` as the goal's feedback (unless it has ended)."""
        if not self.future.done():
            self._handle.publish_feedback(message)


def _nothing() -> None:
    """A task that ends a wait (:meth:`RosNode.wake`)."""

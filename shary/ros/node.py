"""The one ROS 2 node of a shary process, its executor thread and its inbox.

Threading follows what was measured with the Jazzy wheels (docs/ros2.md): one
``Node`` and one ``SingleThreadedExecutor`` spinning in a daemon thread of its
own.  The engine's loop never touches an rclpy object: it *posts* work to the
executor (:meth:`RosNode.post`, which is ``executor.create_task``, the
executor's thread-safe entry), and every ROS callback only *puts an event* on
the inbox, a ``queue.Queue`` of ``(function, args)`` that the engine's loop
drains (:meth:`RosNode.attach`).  Goals are then sent and answered on one
thread, which avoids the wheels' races between threads (rclpy#1123 in Jazzy's
``ActionClient``); ``EventsExecutor`` is not used (it deadlocked here).

Shutdown is ordered as rclpy needs it: action clients and servers destroyed on
the executor's thread (``destroy_node`` does not destroy them), then the node,
the executor stopped, the context shut down, and the thread joined, so that no
thread is left behind.
"""

from __future__ import annotations

import queue
import threading
from collections import deque
from collections.abc import Callable
from typing import Any

from shary.ros.env import keep_on_host

BATCH = 500
"""Most messages a drained subscription hands over at once: the executor's thread goes
back to its other entities (a goal's answer) at least this often."""


class RosNode:
    """One node, one executor thread, one inbox (see the module's docstring)."""

    def __init__(self, name: str = "shary", *, domain_id: int | None = None,
                 namespace: str | None = None):
        keep_on_host()
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self._rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node(name, context=self.context, namespace=namespace)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._outbox: deque[tuple[Callable[..., Any], tuple]] = deque()
        self.inbox: queue.SimpleQueue[tuple[Callable[..., Any], tuple]] = queue.SimpleQueue()
        self.waitables: list[Any] = []
        """Action clients and servers, destroyed before the node (rclpy does not)."""
        self._loop: Any = None
        self._closed = False
        self._thread = threading.Thread(target=self._spin, name=f"ros-{name}", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        from rclpy.executors import ExternalShutdownException

        try:
            self.executor.spin()
        except (ExternalShutdownException, KeyboardInterrupt):
            pass

    # -- the two directions ----------------------------------------------------------

    def post(self, work: Callable[..., Any], *args: Any) -> None:
        """Run ``work(*args)`` on the executor's thread, after the work posted before it:
        the only way the engine acts on ROS.  (The executor runs its pending tasks last
        in, first out; the outbox keeps the engine's order: a goal's cancel after its
        send, a state's publication after the one before.)"""
        if not self._closed:
            self._outbox.append((work, args))
            self.executor.create_task(self._run_outbox)

    def _run_outbox(self) -> None:
        while self._outbox:
            work, args = self._outbox.popleft()
            try:
                work(*args)
            except Exception as err:  # noqa: BLE001 -- raised again on the engine's loop
                self.put(_raise, err)

    def put(self, handler: Callable[..., Any], *args: Any, wake: bool = True) -> None:
        """From a ROS callback: have ``handler(*args)`` run on the engine's loop (with
        ``wake=False``, when the loop next wakes: news that can wait)."""
        loop = self._loop
        if loop is not None:
            loop.call_soon_threadsafe(handler, *args, wake=wake)
        else:
            self.inbox.put((handler, args))

    def wake(self) -> None:
        """From a ROS callback: wake the engine's loop (for events put quietly)."""
        if self._loop is not None:
            self._loop.wake()

    def drain(self) -> int:
        """Run every event waiting in the inbox (on the caller's thread); how many ran."""
        ran = 0
        while True:
            try:
                handler, args = self.inbox.get_nowait()
            except queue.Empty:
                return ran
            handler(*args)
            ran += 1

    def attach(self, loop: Any) -> None:
        """Deliver events to ``loop`` (an :class:`~shary.loop.EventLoop`) from now on,
        starting with those waiting in the inbox."""
        self._loop = loop
        self.drain()

    def call(self, work: Callable[..., Any], *args: Any, timeout: float = 10.0) -> Any:
        """Run ``work(*args)`` on the executor's thread and wait for its value: for
        set-up and shutdown (creating entities), never from the engine's running loop."""
        done = threading.Event()
        box: list[Any] = []

        def run() -> None:
            try:
                box.append((True, work(*args)))
            except BaseException as err:  # noqa: BLE001 -- handed back to the caller
                box.append((False, err))
            finally:
                done.set()

        self.post(run)
        if not done.wait(timeout):
            raise TimeoutError(f"the ROS executor did not run {work!r} within {timeout:g} s")
        ok, value = box[0]
        if not ok:
            raise value
        return value

    # -- entities (created on the executor's thread) ------------------------------------

    def action_client(self, cls: Any, name: str) -> Any:
        from rclpy.action import ActionClient

        client = self.call(ActionClient, self.node, cls, name)
        self.waitables.append(client)
        return client

    def action_server(self, cls: Any, name: str, **callbacks: Any) -> Any:
        from rclpy.action import ActionServer

        server = self.call(lambda: ActionServer(self.node, cls, name, **callbacks))
        self.waitables.append(server)
        return server

    def serve_goals(self, cls: Any, name: str, start: Callable[..., Any],
                    cancel: Callable[[bytes], Any], *,
                    accept: Callable[[Any], str | None] | None = None) -> Any:
        """Serve action ``name`` whose goals are performed on the engine's side: each
        accepted goal puts ``start(key, goal, end)`` on the inbox, ``end`` a
        :class:`ServedGoal` (call it, from any thread, to end the goal; ``end.feedback``
        publishes feedback); a cancel request is accepted at once and puts ``cancel(key)``
        (after ``start``, should it come before the goal runs).  ``accept(goal)``, on the
        executor's thread, answers at once: a reason to reject the goal (logged), or None.
        The execute callback awaits its end on the executor's thread, so no goal holds a
        thread (the shared robot, ``shary world --ros``; ``~/run_task``)."""
        from rclpy.action import CancelResponse, GoalResponse

        live: dict[bytes, Any] = {}
        logger = self.node.get_logger()

        def on_goal(goal: Any) -> Any:
            reason = accept(goal) if accept is not None else None
            if reason is None:
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
            return result

        def on_cancel(handle: Any) -> Any:
            key = bytes(handle.goal_id.uuid)
            if key in live:
                self.put(cancel, key)
            return CancelResponse.ACCEPT

        return self.action_server(cls, name, execute_callback=execute,
                                  goal_callback=on_goal, cancel_callback=on_cancel)

    def service_client(self, cls: Any, name: str) -> Any:
        return self.call(self.node.create_client, cls, name)

    def publisher(self, cls: Any, topic: str, *, latched: bool = False, depth: int = 10,
                  lease: float | None = None) -> Any:
        """A publisher; ``latched``: a late subscriber gets the last message; ``lease``:
        it offers a liveliness lease of that many seconds, asserted as long as this
        process runs (how a supervisor notices it gone: :mod:`shary.ros.liveliness`)."""
        from rclpy.duration import Duration
        from rclpy.qos import DurabilityPolicy, LivelinessPolicy, QoSProfile

        qos = QoSProfile(depth=1 if latched else depth)
        if latched:
            qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
        if lease is not None:
            qos.liveliness = LivelinessPolicy.AUTOMATIC
            qos.liveliness_lease_duration = Duration(seconds=lease)
        return self.call(self.node.create_publisher, cls, topic, qos)

    def subscription(self, cls: Any, topic: str, callback: Callable[[Any], Any], *,
                     depth: int = 100) -> Any:
        """A subscription whose callback runs on the executor's thread (it must only
        :meth:`put` events)."""
        return self.call(self.node.create_subscription, cls, topic, callback, depth)

    def drained_subscription(self, cls: Any, topic: str,
                             callback: Callable[[list[Any]], Any], *, depth: int = 1000,
                             batch: int = BATCH) -> Any:
        """A subscription whose callback gets every message waiting (up to ``batch``) in
        one list, on the executor's thread (it must only :meth:`put` events): for a topic
        that may carry thousands of messages a second (perception).

        rclpy's executor takes one message each time it wakes, and each wake rebuilds its
        wait set in Python over every entity of the node: 3,000-5,000 messages a second
        here, whatever the callback does (docs/benchmarks.md).  Taking the messages that
        wait with the subscription's own ``take_message``, as soon as the first is
        handed over, costs one wake and one event on the engine's loop per burst."""
        holder: list[Any] = []

        def drain(first: Any) -> None:
            taken = [first]
            handle = holder[0].handle
            with handle:  # the handle is not destroyed while it is used
                while len(taken) < batch:
                    got = handle.take_message(cls, False)
                    if got is None:
                        break
                    taken.append(got[0])
            callback(taken)

        def create() -> Any:  # on the executor's thread: before any message is handed over
            holder.append(self.node.create_subscription(cls, topic, drain, depth))
            return holder[0]

        return self.call(create)

    # -- shutdown -----------------------------------------------------------------------

    def close(self, timeout: float = 5.0) -> None:
        """Destroy everything and join the executor's thread (idempotent)."""
        if self._closed:
            return

        def destroy() -> None:
            for waitable in self.waitables:
                waitable.destroy()
            self.node.destroy_node()

        try:
            self.call(destroy, timeout=timeout)
        finally:
            self._closed = True
            self.executor.shutdown(timeout_sec=timeout)
            self._rclpy.try_shutdown(context=self.context)
            self._thread.join(timeout)

    def __enter__(self) -> RosNode:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class ServedGoal:
    """How the engine ends a goal of :meth:`RosNode.serve_goals` and tells its progress,
    from any thread (the work is posted to the executor)."""

    def __init__(self, node: RosNode, handle: Any):
        from rclpy.task import Future

        self._node, self._handle = node, handle
        self.future = Future()
        """Done with ``(result, status)`` when the goal ends (awaited by the server)."""

    def __call__(self, result: Any, canceled: bool = False, failed: bool = False) -> None:
        """End the goal with ``result``: CANCELED if ``canceled`` and a client asked for
        it, ABORTED if ``failed`` (or cancelled unasked), else SUCCEEDED."""
        status = "canceled" if canceled else "aborted" if failed else "succeeded"
        self._node.post(_settle, self.future, (result, status))

    def feedback(self, message: Any) -> None:
        """Publish ``message`` as the goal's feedback (unless it has ended)."""
        self._node.post(_publish_feedback, self.future, self._handle, message)


def _settle(future: Any, value: Any) -> None:
    """End a served goal's wait (on the executor's thread), once."""
    if not future.done():
        future.set_result(value)


def _publish_feedback(future: Any, handle: Any, message: Any) -> None:
    if not future.done():
        handle.publish_feedback(message)


def _raise(err: Exception) -> None:
    """An error of work posted to the executor, raised where the engine sees it."""
    raise err

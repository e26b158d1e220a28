"""Noticing that a node of the robot is gone: ROS 2 liveliness with a lease.

A robot driver that dies is the commonest failure on a real robot, and ROS 2
hides it: a node killed with SIGKILL stays in the graph, and its action
servers look ready, for the DDS participant's lease (20 s with Fast DDS),
while the results of its goals never come.  What ROS 2 offers for this is the
liveliness QoS policy: a publisher offers a lease, the middleware asserts its
liveliness (``AUTOMATIC``: as long as its process runs), and a subscriber that
requests a lease at least as long is told as soon as no assertion came within
it (measured here: a SIGKILLed publisher offering 0.5 s, noticed 1.0 s later;
one that exits cleanly, at once).  It is what the ROS 2 software watchdogs
(ros-safety/software_watchdogs) are built on; the graph is not used, since it
keeps a killed node for 20 s.

So a binding's ``alive:`` names, for each node of the robot, a topic whose
publishers offer a lease (the simulated Jido's fact topic offers 0.5 s), the
lease shary asks for, and the atomic tasks that node performs.  shary
subscribes to it with that lease (a subscription of its own: a publisher
offering no lease is incompatible with it, never with perception) and, when
the last publisher's liveliness ends:

* the goals in flight of the node's tasks fail at once, outcome ``node gone``,
  the reason naming the node (``the robot's node /jido_sim is gone …``), and
  its tasks fail at once until it is back, as a missing server does;
* a ``ros-alive`` row says so, and :attr:`Liveliness.gone` holds the reason,
  for whoever runs the supervisor to end the run (``shary run --ros``).

The lease is shary's own deadline, as every other one: a node is gone when
shary's lease says so, not when ROS gets round to it.  A publisher that offers
no lease short enough is logged once (``incompatible``): shary cannot notice
that node go.

The subscription's callbacks run while the engine's loop waits, and only put events
on it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from shary.ros.binding import AliveSource, Binding, import_interface
from shary.ros.node import RosNode


class Liveliness:
    """The liveliness of the robot's nodes named by a binding (see the module's docstring)."""

    def __init__(self, node: RosNode, binding: Binding, *, executors: Any,
                 record: Callable[..., Any] | None = None):
        self.node = node
        self.executors = executors
        """Told of a node gone and back (``node_gone(tasks, reason)``, ``node_back(tasks)``)."""
        self.record = record or (lambda *args, **data: None)
        self.gone: list[str] = []
        """Why each node that went is gone, in the order they went (empty: all there)."""
        self.watchers: list[Callable[[str], Any]] = []
        """Called with the reason when a node goes (on the engine's loop)."""
        self._nodes: dict[int, list[str]] = {}
        """The publishers' nodes of each source, as last seen alive."""
        self._alive: set[int] = set()
        """The sources seen alive once."""
        self._down: dict[int, str] = {}
        self._incompatible: set[int] = set()
        for index, source in enumerate(binding.alive):
            cls = import_interface(source.type)
            if cls is not None:
                self._subscribe(index, source, cls)

    def _subscribe(self, index: int, source: AliveSource, cls: Any) -> Any:
        """A subscription that asks for the source's lease."""
        from rclpy.duration import Duration
        from rclpy.event_handler import SubscriptionEventCallbacks
        from rclpy.qos import LivelinessPolicy, QoSProfile

        rcl = self.node.node
        qos = QoSProfile(depth=1, liveliness=LivelinessPolicy.AUTOMATIC,
                         liveliness_lease_duration=Duration(seconds=source.lease))

        def changed(info: Any) -> None:
            # the graph still lists a killed node (for the DDS lease): asked again as it
            # goes, since a publisher's node may not be known yet when it comes
            names = [_full_name(p) for p in rcl.get_publishers_info_by_topic(source.topic)
                     if _offers(p, source.lease) and UNKNOWN not in p.node_name]
            self.node.put(self._changed, index, source, info.alive_count,
                          info.not_alive_count_change > 0, names)

        def incompatible(info: Any) -> None:
            self.node.put(self._incompatible_qos, index, source)

        return rcl.create_subscription(
            cls, source.topic, lambda message: None, qos,
            event_callbacks=SubscriptionEventCallbacks(liveliness=changed,
                                                       incompatible_qos=incompatible))

    # -- on the engine's loop ----------------------------------------------------------

    def _changed(self, index: int, source: AliveSource, alive: int, lapsed: bool,
                 names: list[str]) -> None:
        if names or index not in self._nodes:
            self._nodes[index] = names or self._nodes.get(index, [])
        if alive:
            self._alive.add(index)
            if index in self._down:
                self.record("ros-alive", topic=source.topic, nodes=self._nodes[index],
                            state="back")
                reason = self._down.pop(index)
                if reason in self.gone:
                    self.gone.remove(reason)
                self.executors.node_back(source.tasks)
            return
        if index in self._down or index not in self._alive:
            return  # gone already, or never seen alive (the robot is not up yet)
        who = ", ".join(self._nodes[index]) or f"publishing on {source.topic}"
        how = (f"its liveliness on {source.topic} lapsed: lease {source.lease:g} s" if lapsed
               else f"its publisher on {source.topic} left")
        reason = f"the robot's node {who} is gone ({how})"
        self._down[index] = reason
        self.gone.append(reason)
        self.record("ros-alive", topic=source.topic, nodes=self._nodes[index], state="gone",
                    reason=reason)
        self.executors.node_gone(source.tasks, reason)
        for watcher in list(self.watchers):
            watcher(reason)

    def _incompatible_qos(self, index: int, source: AliveSource) -> None:
        if index in self._incompatible:
            return
        self._incompatible.add(index)
        self.record("ros-alive", topic=source.topic, state="incompatible",
                    reason=f"a publisher on {source.topic} offers no liveliness lease of at "
                    f"most {source.lease:g} s: shary cannot notice its node go")


UNKNOWN = "_NODE_NAME_UNKNOWN_"
"""What the graph says of a publisher whose node is not known yet."""


def _full_name(info: Any) -> str:
    """A publisher's node as ``ros2 node list`` shows it."""
    namespace = info.node_namespace.rstrip("/")
    return f"{namespace}/{info.node_name}"


def _offers(info: Any, lease: float) -> bool:
    """Whether a publisher offers a liveliness lease that ``lease`` accepts."""
    offered = info.qos_profile.liveliness_lease_duration.nanoseconds
    return 0 < offered <= lease * 1e9

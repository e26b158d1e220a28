"""Quality of service per topic, as the binding says, and publishers that do not match.

A robot's topics do not all speak alike: a camera's or a tracker's publisher is
best-effort (``sensor-data``), and a reliable subscription never hears it; a map or a
robot's description is *latched* (transient local), and a volatile subscription misses
what was sent before it came.  Each fact and speech topic of a binding, and each topic a
task publishes on, may therefore say its ``qos:``

* a preset: ``sensor-data`` (best-effort, volatile, keep the last 5), ``latched``
  (reliable, transient local, keep the last 1) or ``default`` (reliable, volatile, keep
  the last 10), rclpy's own profiles;
* or the policies, over a preset or shary's default for that topic: ``reliability``
  (``reliable``, ``best-effort``), ``durability`` (``volatile``, ``transient-local``),
  ``history`` (``keep-last``, ``keep-all``) and ``depth``.

Without ``qos:`` a topic keeps shary's default for it (perception: reliable, volatile,
a deep history, :data:`shary.ros.perception.DEPTH`).

A publisher whose offer the subscription cannot accept (a best-effort publisher of a
reliable subscription, a volatile one of a transient-local subscription) is reported
as soon as the middleware matches them, at start-up or when it appears, through rclpy's
incompatible-QoS event: a ``ros-qos`` row and :attr:`QosWatch.watchers` (``shary ros``
prints it), naming the topic, the policy, and both profiles.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

UNKNOWN = "_NODE_NAME_UNKNOWN_"
"""What the graph says of a publisher whose node is not known yet."""
NAME_POLL, NAMED_WITHIN = 0.1, 20
"""Seconds between two looks for an incompatible publisher's node, and how many looks."""


def profile(spec: Any, default: Any) -> Any:
    """The rclpy ``QoSProfile`` for a binding's ``qos:`` (a preset name, a mapping of
    policies, or None for ``default``, a ``QoSProfile``; None: rclpy's default)."""
    from rclpy.qos import (
        DurabilityPolicy,
        HistoryPolicy,
        QoSProfile,
        ReliabilityPolicy,
        qos_profile_default,
        qos_profile_sensor_data,
    )

    if spec is None:
        return default
    policies = {"preset": spec} if isinstance(spec, str) else dict(spec)
    base = {"sensor-data": qos_profile_sensor_data, "default": qos_profile_default,
            "latched": QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL),
            None: qos_profile_default if default is None else default}[policies.get("preset")]
    made = QoSProfile(history=base.history, depth=base.depth, reliability=base.reliability,
                      durability=base.durability)
    if "reliability" in policies:
        made.reliability = {"reliable": ReliabilityPolicy.RELIABLE,
                            "best-effort": ReliabilityPolicy.BEST_EFFORT}[
            policies["reliability"]]
    if "durability" in policies:
        made.durability = {"volatile": DurabilityPolicy.VOLATILE,
                           "transient-local": DurabilityPolicy.TRANSIENT_LOCAL}[
            policies["durability"]]
    if "history" in policies:
        made.history = {"keep-last": HistoryPolicy.KEEP_LAST,
                        "keep-all": HistoryPolicy.KEEP_ALL}[policies["history"]]
    if "depth" in policies:
        made.depth = int(policies["depth"])
    return made


def describe(qos: Any) -> str:
    """A profile as the binding writes it: ``best-effort, volatile, keep-last 5``."""
    def name(policy: Any) -> str:
        return policy.name.lower().replace("_", "-")

    history = name(qos.history)
    return (f"{name(qos.reliability)}, {name(qos.durability)}, "
            + (f"{history} {qos.depth}" if history == "keep-last" else history))


class QosWatch:
    """Reports publishers whose offer a subscription of the node cannot accept (see the
    module's docstring); its :meth:`callbacks` go to a subscription's
    ``event_callbacks``."""

    def __init__(self, node: Any, loop: Any, record: Callable[..., Any]):
        self.node = node
        """The :class:`~shary.ros.node.RosNode`."""
        self.loop = loop
        self.record = record
        self.watchers: list[Callable[[str], Any]] = []
        """Called with the text of each report (on the engine's loop)."""
        self.reported: set[tuple[str, str]] = set()
        """(topic, publisher's node) already reported: once each."""

    def callbacks(self, topic: str, asked: Any) -> Any:
        """The event callbacks of a subscription to ``topic`` asking ``asked``."""
        from rclpy.event_handler import SubscriptionEventCallbacks

        def incompatible(info: Any) -> None:
            policy = info.last_policy_kind.name.lower().removeprefix("rmw_qos_policy_")
            self.node.put(self._incompatible, topic, asked, policy, NAMED_WITHIN)

        return SubscriptionEventCallbacks(incompatible_qos=incompatible)

    def _incompatible(self, topic: str, asked: Any, policy: str, tries: int) -> None:
        from rclpy.qos import QoSCompatibility, qos_check_compatible

        found = [info for info in self.node.node.get_publishers_info_by_topic(topic)
                 if qos_check_compatible(info.qos_profile, asked)[0] == QoSCompatibility.ERROR]
        if tries and any(UNKNOWN in info.node_name for info in found):
            # the graph learns a publisher's node a little after the publisher itself
            self.loop.call_later(NAME_POLL, self._incompatible, topic, asked, policy, tries - 1)
            return
        for info in found:
            offered = info.qos_profile
            who = (f"{info.node_namespace.rstrip('/')}/{info.node_name}"
                   if UNKNOWN not in info.node_name else "a node not known yet")
            if (topic, who) in self.reported:
                continue
            self.reported.add((topic, who))
            text = (f"{topic}: the publisher of {who} offers {describe(offered)}, which "
                    f"shary's subscription ({describe(asked)}) cannot accept "
                    f"({policy}): nothing it sends arrives; say the topic's qos: in the "
                    "binding")
            self.record("ros-qos", topic=topic, publisher=who, offered=describe(offered),
                        asked=describe(asked), policy=policy, reason=text)
            for watcher in list(self.watchers):
                watcher(text)

"""A robot's topics for the tests, in a process of their own (std_msgs/String only).

Reads commands on standard input, one a line: ``pub TOPIC TEXT`` publishes
TEXT (``\\n`` for a new line) on TOPIC, repeated every 0.1 s (as perception
does) until changed; ``stop TOPIC`` stops publishing there; ``once TOPIC TEXT``
publishes TEXT once, when the topic has a subscriber (what a person says);
``burst TOPIC N TEXT`` publishes N messages at once, when the topic has a
subscriber, ``{i}`` in TEXT replaced by each one's number (perception faster
than one message per wake of the subscriber's executor); ``sensor TOPIC TEXT`` publishes
like ``pub`` but best-effort (sensor data); ``latch TOPIC TEXT`` publishes TEXT once on a
latched (transient local) publisher, at once, subscriber or not.
Prints ``ready``, ``heard TOPIC TEXT`` for each message on the topics named
on the command line (the robot's speech, shary's state topics), each
``TOPIC`` (a String), ``TOPIC=latched`` (a latched String),
``TOPIC=DiagnosticArray`` (``NAME|LEVEL|MESSAGE`` per status) or
``TOPIC=MarkerArray`` (the markers' texts).
"""

from __future__ import annotations

import sys
import threading

import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from std_msgs.msg import String


def main() -> None:
    rclpy.init()
    node = rclpy.create_node("test_robot")
    lock = threading.Lock()
    publishers: dict[str, object] = {}
    current: dict[str, str] = {}
    kinds: dict[str, str] = {}
    """A topic's publisher's kind: sensor (best-effort) or latched; reliable else."""
    once: list[tuple[str, str]] = []
    bursts: list[tuple[str, int, str]] = []

    def listen(spec: str) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.qos import DurabilityPolicy, QoSProfile
        from visualization_msgs.msg import MarkerArray

        topic, _, kind = spec.partition("=")
        cls, show, qos = String, (lambda m: m.data), QoSProfile(depth=10)
        if kind == "latched":
            qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        elif kind == "DiagnosticArray":
            cls = DiagnosticArray
            show = lambda m: "; ".join(f"{s.name}|{s.level[0]}|{s.message}"  # noqa: E731
                                       for s in m.status)
        elif kind == "MarkerArray":
            cls, show = MarkerArray, lambda m: "; ".join(k.text for k in m.markers)  # noqa: E731
        node.create_subscription(cls, topic, lambda m: print("heard", topic, show(m),
                                                             flush=True), qos)

    for spec in sys.argv[1:]:
        listen(spec)

    def publisher(topic: str):
        from rclpy.qos import DurabilityPolicy, QoSProfile, qos_profile_sensor_data

        if topic not in publishers:
            qos = {"sensor": qos_profile_sensor_data,
                   "latched": QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
                   }.get(kinds.get(topic, ""), 1000)  # a burst's room
            publishers[topic] = node.create_publisher(String, topic, qos)
        return publishers[topic]

    def tick() -> None:
        with lock:
            for topic, text in current.items():
                publisher(topic).publish(String(data=text))
            for topic, text in list(once):
                if publisher(topic).get_subscription_count():
                    publisher(topic).publish(String(data=text))
                    once.remove((topic, text))
            for topic, count, text in list(bursts):
                if publisher(topic).get_subscription_count():
                    for i in range(count):
                        publisher(topic).publish(String(data=text.replace("{i}", str(i))
                                                        .replace("\\n", "\n")))
                    bursts.remove((topic, count, text))

    node.create_timer(0.1, tick)

    def commands() -> None:
        for line in sys.stdin:
            word, _, rest = line.rstrip("\n").partition(" ")
            topic, _, text = rest.partition(" ")
            with lock:
                if word in ("pub", "sensor"):
                    kinds.setdefault(topic, "sensor" if word == "sensor" else "")
                    current[topic] = text.replace("\\n", "\n")
                elif word == "latch":
                    kinds[topic] = "latched"
                    publisher(topic).publish(String(data=text.replace("\\n", "\n")))
                elif word == "once":
                    once.append((topic, text))
                elif word == "burst":
                    count, _, text = text.partition(" ")
                    bursts.append((topic, int(count), text))
                elif word == "stop":
                    current.pop(topic, None)
        rclpy.try_shutdown()

    threading.Thread(target=commands, daemon=True).start()
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    print("ready", flush=True)
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == "__main__":
    main()

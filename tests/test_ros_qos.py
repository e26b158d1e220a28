"""Quality of service per topic from the binding, against a robot in another process: a
latched topic's facts sent before shary came arrive, a best-effort (sensor data) topic
is heard, and a publisher shary's subscription cannot accept is reported naming the
topic, the policy and both profiles."""

from __future__ import annotations

from conftest import problems
from rosfixtures import needs_ros, run_until

from shary.facts.database import FactDatabase
from shary.kernel.loop import EventLoop, WallClock
from shary.ros.binding import load_binding

BINDING = """\
    binding: test
    robot: jido
    tasks:
      speak: {topic: /robot/say, type: std_msgs/msg/String, goal: {data: "{text}"}, QOS}
    facts:
      - {topic: /robot/facts, type: std_msgs/msg/String, lines: data, QOS}
    """


def perceive(write, ros_domain, qos: str):
    """A node perceiving /robot/facts with ``qos`` (a binding's ``qos: …``, or empty):
    the loop, the facts, the node, the rows logged and what the watch reported."""
    from shary.ros.node import RosNode
    from shary.ros.perception import RosPerception
    from shary.ros.qos import QosWatch

    text = BINDING.replace(", QOS", f", {qos}" if qos else "")
    binding = load_binding(write("binding.yaml", text))
    loop, facts = EventLoop(WallClock()), FactDatabase()
    rows: list[tuple[str, dict]] = []
    reports: list[str] = []
    node = RosNode("shary_qos", domain_id=ros_domain)
    node.attach(loop)
    watch = QosWatch(node, loop, lambda kind, **data: rows.append((kind, data)))
    watch.watchers.append(reports.append)
    RosPerception(node, binding, facts, loop, qos=watch)
    return loop, facts, node, rows, reports


@needs_ros
def test_a_latched_topic_s_facts_sent_before_shary_came_arrive(write, ros_domain, spawn):
    robot = spawn("tests/ros_robot.py")
    robot.wait_for("ready")
    robot.send("latch /robot/facts kitchen position \"1 2 0\"")
    loop, facts, node, rows, reports = perceive(write, ros_domain, "qos: latched")
    with node:
        run_until(loop, lambda: facts.objects("kitchen", "position"))
        assert not reports


@needs_ros
def test_a_best_effort_topic_is_heard_with_the_sensor_data_preset(write, ros_domain, spawn):
    robot = spawn("tests/ros_robot.py")
    robot.wait_for("ready")
    robot.send("sensor /robot/facts alice looksAt jido")
    loop, facts, node, rows, reports = perceive(write, ros_domain, "qos: sensor-data")
    with node:
        run_until(loop, lambda: facts.holds("alice", "looksAt", "jido"))
        assert not reports


@needs_ros
def test_a_publisher_shary_cannot_hear_is_reported_with_both_profiles(write, ros_domain,
                                                                       spawn):
    robot = spawn("tests/ros_robot.py")
    robot.wait_for("ready")
    robot.send("sensor /robot/facts alice looksAt jido")
    loop, facts, node, rows, reports = perceive(write, ros_domain, "")
    with node:
        run_until(loop, lambda: reports)
        [(kind, row)] = rows
        assert kind == "ros-qos" and row["topic"] == "/robot/facts"
        assert row["publisher"] == "/test_robot" and row["policy"] == "reliability"
        assert row["offered"].startswith("best-effort, volatile")
        assert row["asked"] == "reliable, volatile, keep-last 10000"
        assert reports[0].startswith("/robot/facts: the publisher of /test_robot offers "
                                     "best-effort, volatile")
        assert "shary's subscription (reliable, volatile, keep-last 10000) cannot accept " \
            "(reliability)" in reports[0]
        # a second publisher of the same kind appears later: reported when it appears
        robot.send("sensor /robot/other x y z")
        loop.run_for(0.2)
        assert len(reports) == 1  # the same node on the same topic: once


@needs_ros
def test_a_volatile_publisher_of_a_latched_subscription_is_reported(write, ros_domain,
                                                                    spawn):
    robot = spawn("tests/ros_robot.py")
    robot.wait_for("ready")
    robot.send("pub /robot/facts alice looksAt jido")
    loop, facts, node, rows, reports = perceive(write, ros_domain, "qos: latched")
    with node:
        run_until(loop, lambda: reports)
        assert rows[0][1]["policy"] == "durability"
        assert rows[0][1]["asked"] == "reliable, transient-local, keep-last 1"


@needs_ros
def test_presets_and_policies_make_rclpy_s_profiles():
    from rclpy.qos import QoSProfile

    from shary.ros.qos import describe, profile

    default = QoSProfile(depth=10000)
    assert describe(profile(None, default)) == "reliable, volatile, keep-last 10000"
    assert describe(profile("sensor-data", default)) == "best-effort, volatile, keep-last 5"
    assert describe(profile("latched", default)) == "reliable, transient-local, keep-last 1"
    assert describe(profile({"preset": "latched", "depth": 3}, default)) == (
        "reliable, transient-local, keep-last 3")
    assert describe(profile({"reliability": "best-effort", "history": "keep-all"},
                            default)) == "best-effort, volatile, keep-all"


def test_qos_is_checked_when_a_binding_is_validated(shary, write):
    path = write("robot.yaml", """\
        binding: bad
        robot: jido
        tasks:
          navigate: {action: /nav, type: test_msgs/action/Fibonacci, qos: latched}
        """)
    status, _, err = shary("validate", path)
    assert status == 2
    [found] = problems(err)
    assert (found["line"], found["col"]) == ("4", "62")
    assert "an action has no qos: only a topic task has" in found["message"]
    path = write("robot.yaml", """\
        binding: bad
        robot: jido
        tasks: {}
        facts:
          - {topic: /f, type: std_msgs/msg/String, lines: data, qos: {depth: 0}}
          - {topic: /g, type: std_msgs/msg/String, lines: data, qos: fast}
        """)
    status, _, err = shary("validate", path)
    assert status == 2
    assert [(m["line"], m["col"]) for m in problems(err)] == [("5", "70"), ("6", "62")]

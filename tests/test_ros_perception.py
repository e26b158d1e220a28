"""Perception, people and speech through ROS 2 topics, against a robot in another process:
facts in (only changes reach the database), stale topics, a person's answer and request,
and the robot's speech out."""

from __future__ import annotations

from rosfixtures import needs_ros, run_until

from shary.facts.database import FactDatabase
from shary.kernel.executors import Reporter, Request
from shary.kernel.loop import EventLoop, WallClock
from shary.ros.binding import FactSource, load_binding
from shary.ros.perception import RosPerception

pytestmark = needs_ros

BINDING = """\
    binding: test
    robot: jido
    tasks:
      speak: {topic: /robot/say, type: std_msgs/msg/String, goal: {data: "{text}"}}
    facts:
      - {topic: /robot/facts, type: std_msgs/msg/String, lines: data, stale: 500ms}
    speech:
      - {topic: /robot/heard/alice, type: std_msgs/msg/String, text: data, speaker: alice}
    """


def test_facts_in_stale_facts_out_speech_in_and_out(write, ros_domain, spawn):
    from shary.ros.executors import RosExecutors
    from shary.ros.node import RosNode

    binding = load_binding(write("binding.yaml", BINDING))
    robot = spawn("tests/ros_robot.py", "/robot/say")
    robot.wait_for("ready")
    loop, facts = EventLoop(WallClock()), FactDatabase()
    changes, acts, heard, rows = [], [], [], []
    facts.subscribe(lambda event: changes.append(event))
    with RosNode("shary_perception", domain_id=ros_domain) as node:
        node.attach(loop)
        RosPerception(node, binding, facts, loop, act=lambda *a: acts.append(a),
                      hear=lambda *a: heard.append(a),
                      record=lambda kind, **data: rows.append((kind, data)))
        executors = RosExecutors(node, binding, loop,
                                 record=lambda kind, **data: rows.append((kind, data)))
        robot.send(r"pub /robot/facts alice looksAt jido\nalice isAt sofa-area")
        run_until(loop, lambda: facts.holds("alice", "looksAt", "jido"))
        loop.run_for(0.3)  # three more identical messages: no change reaches the database
        assert len(changes) == 2
        robot.send("pub /robot/facts alice isAt sofa-area")  # she looks away
        run_until(loop, lambda: not facts.holds("alice", "looksAt", "jido"))
        assert facts.holds("alice", "isAt", "sofa-area") and len(changes) == 3
        robot.send("stop /robot/facts")  # no longer tracked: no longer perceived
        run_until(loop, lambda: not facts.holds("alice", "isAt", "sofa-area"))
        assert ("stale", {"topic": "/robot/facts", "facts": 1}) in rows

        robot.send("once /robot/heard/alice Yes.")
        run_until(loop, lambda: acts == [("alice", "H-AGREE")])
        robot.send("once /robot/heard/alice bring me the yellow bottle")
        run_until(loop, lambda: heard == [("alice", "bring me the yellow bottle")])

        outcomes = []
        executors.start(Request("r1", "speak", {"text": "Here is your bottle."}, "jido", "n1"),
                        Reporter(outcomes.append, loop.call_soon))
        run_until(loop, lambda: "heard /robot/say Here is your bottle." in robot.lines)
        assert [o.status for o in outcomes] == ["done"]
        # the log says what the robot said, as a simulated run's does (a scenario's `said`)
        assert ("speech", {"agent": "jido", "text": "Here is your bottle.", "request": "r1"}) \
            in rows


def test_a_burst_of_perception_becomes_facts_message_by_message(write, ros_domain, spawn):
    """Messages that come faster than one a wake of the executor are taken together
    (drained) and each one's facts are still a change of their own, made whole before
    anyone hears of it: her gaze moves from one thing to the next, never to nothing."""
    from shary.ros.node import RosNode

    binding = load_binding(write("binding.yaml", BINDING))
    robot = spawn("tests/ros_robot.py")
    robot.wait_for("ready")
    loop, facts = EventLoop(WallClock()), FactDatabase()
    seen = []
    facts.subscribe(lambda e: seen.append((e.kind, e.object, facts.objects("alice", "looksAt"))),
                    subject="alice", predicate="looksAt")
    with RosNode("shary_burst", domain_id=ros_domain) as node:
        node.attach(loop)
        perception = RosPerception(node, binding, facts, loop)
        robot.send(r"burst /robot/facts 300 alice looksAt thing-{i}\nalice isAt sofa-area")
        run_until(loop, lambda: facts.holds("alice", "looksAt", "thing-299"))
    assert perception.messages == 300
    assert [o for kind, o, _ in seen if kind == "added"] == [f"thing-{i}" for i in range(300)]
    assert all(now == [f"thing-{int(o[6:]) + 1}"] for kind, o, now in seen if kind == "removed")


def test_templates_make_one_fact_per_element_of_a_sequence():
    from diagnostic_msgs.msg import DiagnosticStatus, KeyValue

    source = FactSource("/gaze", "diagnostic_msgs/msg/DiagnosticStatus",
                        (("{item.key}", "looksAt", "{item.value}"),
                         ("{name}", "sees", "{item.key}")), each="values")
    message = DiagnosticStatus(name="camera", values=[KeyValue(key="alice", value="jido"),
                                                      KeyValue(key="bob", value="tv")])
    assert RosPerception.triples(source, message) == {
        ("alice", "looksAt", "jido"), ("bob", "looksAt", "tv"),
        ("camera", "sees", "alice"), ("camera", "sees", "bob")}



def test_lines_carry_truth_values_numbers_and_text_literals_as_such():
    from rdflib import Literal
    from std_msgs.msg import String

    source = FactSource("/jido/facts", "std_msgs/msg/String", lines="data")
    message = String(data='yellow-bottle robot_reach false\njido move_cost 2\n'
                          'alice position "0.12 0.00 0.56"\nalice looksAt jido\n'
                          'yellow-bottle color "yellow"')
    found = RosPerception.triples(source, message)
    assert found == {("yellow-bottle", "robot_reach", False), ("jido", "move_cost", 2),
                     ("alice", "position", Literal("0.12 0.00 0.56")),
                     ("alice", "looksAt", "jido"), ("yellow-bottle", "color", Literal("yellow"))}
    facts = FactDatabase()
    for triple in found:  # each one a fact the database takes
        facts.add(*triple)
    assert facts.objects("yellow-bottle", "robot_reach") == [False]


def test_a_line_that_names_nothing_is_refused_and_the_rest_are_facts(write, ros_domain):
    """A robot's perception may send anything: a line whose name has an unknown prefix
    (``foo:x``) or is no name at all is refused with a row that says why, and the other
    lines of the message still become facts; the engine's loop goes on."""
    from std_msgs.msg import String

    from shary.ros.node import RosNode

    binding = load_binding(write("binding.yaml", BINDING))
    loop, facts, rows = EventLoop(WallClock()), FactDatabase(), []
    with RosNode("shary_bad_lines", domain_id=ros_domain) as node:
        node.attach(loop)
        RosPerception(node, binding, facts, loop,
                      record=lambda kind, **data: rows.append((kind, data)))
        publish = node.publisher(String, "/robot/facts", depth=10)
        publish.publish(String(data="alice looksAt jido\na b foo:x\nbob sees a?b"))
        run_until(loop, lambda: facts.holds("alice", "looksAt", "jido"))
        loop.run_for(0.2)
        assert facts.objects("a", "b") == [] and facts.objects("bob", "sees") == []
        refused = [data for kind, data in rows if kind == "refused"]
        assert sorted(r["line"] for r in refused) == ["a b foo:x", "bob sees a?b"]
        assert all(r["topic"] == "/robot/facts" and r["reason"] for r in refused)
        publish.publish(String(data="alice looksAt tv"))
        run_until(loop, lambda: facts.holds("alice", "looksAt", "tv"))

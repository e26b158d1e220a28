"""shary as a node other nodes talk to: a plain rclpy process asks for a task over
``~/run_task``, answers for the person over ``~/person_act``, and sees the verdict, the
feedback, the active states, the latched snapshot, ``/diagnostics`` and the markers; the
node shuts down leaving no thread behind."""

from __future__ import annotations

import json
import threading

from rosfixtures import needs_ros, run_until

from shary.facts import FactDatabase
from shary.loop import EventLoop, WallClock
from shary.ros.binding import load_binding

pytestmark = needs_ros

TOPICS = ("/shary/run_task/result", "/shary/run_task/feedback", "/shary/active_state",
          "/shary/snapshot=latched", "/diagnostics=DiagnosticArray",
          "/shary/markers=MarkerArray", "/jido/say")


FEEDBACK = "/shary/run_task/feedback"


def heard(process, topic: str) -> list[str]:
    prefix = f"heard {topic} "
    return [line[len(prefix):] for line in process.lines if line.startswith(prefix)]


def test_a_plain_rclpy_client_asks_for_a_task_and_gets_the_verdict(write, ros_domain, spawn):
    from scripted import ScriptedExecutor

    from shary.executors import ExecutorRegistry
    from shary.io.recipes import load_library
    from shary.ros.bridge import RosSupervision
    from shary.ros.node import RosNode
    from shary.supervisor import Supervisor
    from shary.told import Told

    before = set(threading.enumerate())
    binding = load_binding(write("jido.yaml", """\
        binding: jido
        robot: jido
        tasks:
          speak: {topic: /jido/say, type: std_msgs/msg/String, goal: {data: "{text}"}}
        """))
    loop, facts = EventLoop(WallClock()), FactDatabase()
    for triple in (("alice", "looksAt", "jido"), ("bottle", "isOn", "table"),
                   ("bottle", "isReachableBy", "jido"), ("alice", "type", "Human")):
        facts.add(*triple)
    library = load_library()
    scripted = ScriptedExecutor(loop, durations=dict.fromkeys(library.atomic, 0.05))
    fanout = Told()
    sup = Supervisor(library, facts, robot="jido", loop=loop, log=fanout,
                     executors=ExecutorRegistry({name: scripted for name in library.atomic}))
    client = spawn("tests/ros_robot.py", *TOPICS)
    client.wait_for("ready")
    node = RosNode("shary", domain_id=ros_domain)
    RosSupervision(sup, binding, node, fanout=fanout)
    goal = {"id": "g1", "task": "give-object", "with": {"object": "bottle", "partner": "alice"}}
    client.send("once /shary/run_task/goal " + json.dumps(goal))
    run_until(loop, lambda: any('"jido: ASK' in f for f in heard(client, FEEDBACK)))
    client.send("once /shary/person_act " + json.dumps({"agent": "alice", "act": "H-AGREE"}))
    run_until(loop, lambda: heard(client, "/shary/run_task/result"))
    result = json.loads(heard(client, "/shary/run_task/result")[0])
    assert result == {"id": "g1", "verdict": "done", "reason": ""}

    client.send("once /shary/run_task/goal " + json.dumps({"id": "g2", "task": "fly"}))
    run_until(loop, lambda: len(heard(client, "/shary/run_task/result")) == 2)
    rejected = json.loads(heard(client, "/shary/run_task/result")[1])
    assert rejected["verdict"] == "rejected" and "no task 'fly'" in rejected["reason"]

    # the robot spoke through its binding; the tools saw the task's states
    assert heard(client, "/jido/say")
    states = heard(client, "/shary/active_state")
    assert states[0] == "give-object n1: ask" and states[-1] == "give-object n1: ended"
    assert "give-object n1: realize, engaged, handover" in states
    run_until(loop, lambda: any("shary/give-object" in d and "|0|ended: done" in d
                                for d in heard(client, "/diagnostics")))
    snapshot = json.loads(heard(client, "/shary/snapshot")[-1])
    assert [t["outcome"] for t in snapshot["tasks"].values()] == ["done"]
    assert any(m.startswith("jido: ") for m in heard(client, "/shary/markers"))

    node.close()
    left = {t for t in threading.enumerate() if t.name != "test-reader"}
    assert left <= before  # no thread left behind

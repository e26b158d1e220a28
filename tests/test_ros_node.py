"""shary as a node other nodes talk to: a plain rclpy process asks for a task over the
``~/run_task`` action (``tests/ros_client.py``), answers for the person over
``~/person_act``, and sees the feedback, the verdict, a rejection, a cancel, the active
states, the latched snapshot, ``/diagnostics`` and the markers; the node shuts down
leaving no thread behind."""

from __future__ import annotations

import json
import threading

from rosfixtures import needs_ros, run_until

from shary.facts.database import FactDatabase
from shary.kernel.loop import EventLoop, WallClock
from shary.ros.binding import load_binding

pytestmark = needs_ros

TOPICS = ("/shary/active_state", "/shary/snapshot=latched", "/diagnostics=DiagnosticArray",
          "/shary/markers=MarkerArray", "/jido/say")


def heard(process, word: str, gid: str | None = None) -> list[str]:
    """What ``process`` printed after ``word`` (and the goal id ``gid``)."""
    prefix = f"{word} {gid} " if gid is not None else f"{word} "
    return [line[len(prefix):] for line in process.lines if line.startswith(prefix)]


def said(process, line: str) -> bool:
    return line in process.lines


def supervision(write, ros_domain):
    """A supervisor on the wall clock with a scripted robot, its ROS node, and the
    events it logged."""
    from scripted import ScriptedExecutor

    from shary.io.recipes import load_library
    from shary.kernel.executors import ExecutorRegistry
    from shary.kernel.supervisor import Supervisor
    from shary.log.told import Told
    from shary.ros.bridge import RosSupervision
    from shary.ros.node import RosNode

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
    events: list[tuple[str, str | None, dict]] = []
    fanout = Told()
    fanout.listeners.append(lambda time, kind, task, agent, data:
                            events.append((kind, task, data)))
    sup = Supervisor(library, facts, robot="jido", loop=loop, log=fanout,
                     executors=ExecutorRegistry({name: scripted for name in library.atomic}))
    node = RosNode("shary", domain_id=ros_domain)
    RosSupervision(sup, binding, node, fanout=fanout)
    return loop, node, events


GIVE = "give-object object=bottle partner=alice"


def test_a_plain_rclpy_client_asks_for_a_task_and_gets_the_verdict(write, ros_domain, spawn):
    before = set(threading.enumerate())
    client = spawn("tests/ros_client.py")
    robot = spawn("tests/ros_robot.py", *TOPICS)
    loop, node, events = supervision(write, ros_domain)
    # the tools' topics reach the robot's process from the task's first state on
    run_until(loop, lambda: node.node.count_subscribers("/shary/active_state") > 0)
    client.send(f"goal g1 {GIVE}")
    run_until(loop, lambda: "act n1 jido: ASK-TASK" in heard(client, "feedback", "g1"))
    assert said(client, "accepted g1")
    robot.send("once /shary/person_act " + json.dumps({"agent": "alice", "act": "H-AGREE"}))
    run_until(loop, lambda: heard(client, "result", "g1"))
    assert heard(client, "result", "g1") == ["SUCCEEDED done|"]
    feedback = heard(client, "feedback", "g1")
    assert feedback[:2] == ["act n1 jido: ASK-TASK",  # the task's first act, its node
                            'action n3 jido look-at {"target": "alice"}']  # its first action
    assert any(f.startswith("action ") and " jido give " in f for f in feedback)

    # the robot spoke through its binding; the tools saw the task's states
    assert heard(robot, "heard /jido/say")
    # the last state reaches the robot's process on its own topic, maybe after the verdict
    run_until(loop, lambda: "give-object n1: ended" in heard(robot, "heard /shary/active_state"))
    states = heard(robot, "heard /shary/active_state")
    assert states[0] == "give-object n1: asking" and states[-1] == "give-object n1: ended"
    assert "give-object n1: realize, engaged, handover" in states
    run_until(loop, lambda: any("shary/give-object" in d and "|0|ended: done" in d
                                for d in heard(robot, "heard /diagnostics")))
    run_until(loop, lambda: [[t["outcome"] for t in json.loads(last)["tasks"].values()]
                             for last in heard(robot, "heard /shary/snapshot")[-1:]] == [["done"]])
    run_until(loop, lambda: any(m.startswith("jido: ")
                                for m in heard(robot, "heard /shary/markers")))

    node.close()
    left = {t for t in threading.enumerate() if t.name != "test-reader"}
    assert left <= before  # no thread left behind


def test_a_goal_shary_cannot_do_is_rejected_and_a_cancel_cancels_the_task(write, ros_domain,
                                                                          spawn):
    client = spawn("tests/ros_client.py")
    loop, node, events = supervision(write, ros_domain)
    try:
        client.send("goal g1 fly")
        client.send("goal g2 give-object object=bottle")
        run_until(loop, lambda: said(client, "rejected g1") and said(client, "rejected g2"))
        reasons = {data["name"]: data["reason"] for kind, _, data in events
                   if kind == "run-task" and data.get("verdict") == "rejected"}
        assert reasons["fly"].startswith("no task 'fly' (known: ")
        assert reasons["give-object"] == ("task 'give-object' takes object, partner; "
                                          "missing: partner")

        client.send(f"goal g3 {GIVE}")
        run_until(loop, lambda: "act n1 jido: ASK-TASK" in heard(client, "feedback", "g3"))
        client.send("cancel g3")
        client.send("cancel g3")  # twice: the task is cancelled once
        run_until(loop, lambda: heard(client, "result", "g3"))
        assert heard(client, "result", "g3") == [
            "CANCELED cancelled|cancelled by the client of ~/run_task"]
        ends = [data for kind, task, data in events if kind == "task-end" and task == "n1"]
        assert [e["outcome"] for e in ends] == ["cancelled"]
    finally:
        node.close()


def test_the_node_has_no_thread_its_callbacks_and_served_goals_run_on_the_loops(
        ros_domain, monkeypatch):
    """The engine's loop spins the node itself: no thread is started for ROS, a
    subscription's callback and a served goal run on the loop's thread, and a goal served
    and sent by the same node gets its result as soon as the engine ends it (not when the
    loop's wait would have ended)."""
    from std_msgs.msg import String
    from test_msgs.action import NestedMessage

    import shary.ros.node as ros_node
    from shary.ros.node import RosNode

    monkeypatch.setattr(ros_node, "LONGEST_WAIT", 60.0)  # no wait cut short by the cap
    before = set(threading.enumerate())
    loop = EventLoop(WallClock())
    with RosNode("shary_one_thread", domain_id=ros_domain) as node:
        node.attach(loop)
        on: list[tuple[str, int]] = []
        node.subscription(String, "/one/thread",
                          lambda m: on.append((m.data, threading.get_ident())))

        def start(key, goal, end):
            on.append(("goal", threading.get_ident()))
            loop.call_later(0.1, end, NestedMessage.Result())

        node.serve_goals(NestedMessage, "/one/act", start, lambda key: None)
        client = node.action_client(NestedMessage, "/one/act")
        publisher = node.publisher(String, "/one/thread")
        assert set(threading.enumerate()) == before
        run_until(loop, lambda: publisher.get_subscription_count() and client.server_is_ready())
        publisher.publish(String(data="hello"))
        results: list = []
        sent = loop.now()
        client.send_goal_async(NestedMessage.Goal()).add_done_callback(
            lambda f: f.result().get_result_async().add_done_callback(
                lambda r: results.append((r.result().status, loop.now()))))
        loop.run_for(3.0)
        assert sorted(on) == [("goal", threading.get_ident()), ("hello", threading.get_ident())]
        assert [status for status, _ in results] == [4]  # SUCCEEDED
        assert results[0][1] - sent < 1.5
        assert set(threading.enumerate()) == before
    assert loop.waiter is not node


def test_work_from_another_thread_wakes_the_loop_and_its_timers_keep_their_time(
        ros_domain, monkeypatch):
    """While the loop waits in rcl's wait set, work given from another thread runs at once,
    and a timer that work sets fires when due: rclpy's executor, woken by the work's task,
    would otherwise wait on with the timeout it began with (here the 3 s left)."""
    import shary.ros.node as ros_node
    from shary.ros.node import RosNode

    monkeypatch.setattr(ros_node, "LONGEST_WAIT", 60.0)  # no wait cut short by the cap
    loop = EventLoop(WallClock())
    with RosNode("shary_waits", domain_id=ros_domain) as node:
        node.attach(loop)
        seen: list[tuple[str, float]] = []

        def given() -> None:
            seen.append(("given", loop.now()))
            loop.call_later(0.1, lambda: seen.append(("timer", loop.now())))

        threading.Timer(0.2, loop.call_soon_threadsafe, (given,)).start()
        start = loop.now()
        loop.run_for(3.0)
    assert [what for what, _ in seen] == ["given", "timer"]
    assert seen[0][1] - start < 1.5  # woken, not at the end of the wait
    assert seen[1][1] - seen[0][1] < 1.5  # due after 0.1 s, not when the first wait ends

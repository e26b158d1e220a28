"""Stopping ``shary ros`` leaves no robot goal running: SIGINT, SIGTERM, a cancelled
``~/run_task`` goal and the node's shutdown each cancel the goals in flight at a real
server (which records its goals), wait for its answer, end the tasks with ``task-end``
rows and answer the ``~/run_task`` client; a second Ctrl-C abandons the wait and says
what it left."""

from __future__ import annotations

import signal
import time

import pytest
from rosfixtures import needs_ros, run_until

from shary.log.contextlog import read_events

pytestmark = needs_ros

BINDING = """\
binding: stop
robot: jido
codes: {kitchen: 5}
tasks:
  navigate:
    action: /test/ACTION
    type: test_msgs/action/NestedMessage
    goal: {nested_field.int32_value: "{code:place}"}
    deadlines: {server: 20s, exec: 60s, cancel: CANCEL}
"""
TASK = ("--task", "move-for-manipulate", "--with", "place=kitchen")


def executing(server, name: str) -> int:
    """Goals the server is still executing."""
    return server.lines.count(f"running {name}") - server.lines.count(f"over {name}")


def shary_ros(spawn, write, tmp_path, action: str = "long", cancel: str = "3s", *more: str):
    path = write("binding.yaml", BINDING.replace("ACTION", action).replace("CANCEL", cancel))
    return spawn("-m", "shary", "ros", str(path), "--log", str(tmp_path / "log.sqlite"),
                 *more)


@pytest.mark.parametrize("how", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_cancels_the_goal_in_flight_and_ends_the_task(spawn, write, tmp_path, how):
    server = spawn("tests/ros_servers.py", "long")
    server.wait_for("ready")
    shary = shary_ros(spawn, write, tmp_path, "long", "3s", *TASK)
    server.wait_for("running long")
    shary.popen.send_signal(how)
    assert shary.exit_status(30) == 0, shary.lines
    # the server ended the goal as cancelled before shary went
    assert "canceled long" in server.lines and executing(server, "long") == 0
    shary._reader.join(5)
    assert f"stopping (shary stopped by {how.name}): 1 task(s) cancelled, " \
        "1 robot goal(s) cancelled" in shary.lines
    assert "  navigate on /test/long (r1): confirmed" in shary.lines
    assert shary.lines[-1] == "shary stopped"
    rows = [(e.kind, e.task, e.data) for e in read_events(tmp_path / "log.sqlite")]
    assert ("task-end", "n1", {"name": "move-for-manipulate", "outcome": "cancelled",
                               "reason": f"shary stopped by {how.name}"}) in rows
    assert "confirmed" in [d["state"] for k, _, d in rows if k == "ros-cancel"]
    [stop] = [d for k, _, d in rows if k == "ros-stop"]
    assert stop["goals"] == ["navigate on /test/long (r1): confirmed"]


def test_a_second_ctrl_c_exits_at_once_saying_what_it_left(spawn, write, tmp_path):
    """The server accepts the cancel but never ends the goal (hang), and the cancel
    deadline is long: the second Ctrl-C abandons the wait."""
    server = spawn("tests/ros_servers.py", "hang")
    server.wait_for("ready")
    shary = shary_ros(spawn, write, tmp_path, "hang", "60s", *TASK)
    server.wait_for("running hang")
    shary.popen.send_signal(signal.SIGINT)
    server.wait_for("cancel-requested hang")
    shary.popen.send_signal(signal.SIGINT)
    assert shary.exit_status(20) == 1, shary.lines
    shary._reader.join(5)
    assert "abandoned the stop: left 1 robot goal(s) whose cancel was not answered: " \
        "navigate on /test/hang (r1)" in shary.lines
    [stop] = [e.data for e in read_events(tmp_path / "log.sqlite", kind="ros-stop")]
    assert stop["left"] == ["navigate on /test/hang (r1)"]


def test_a_cancel_that_is_not_answered_is_waited_for_up_to_its_deadline(spawn, write,
                                                                         tmp_path):
    server = spawn("tests/ros_servers.py", "hang")
    server.wait_for("ready")
    shary = shary_ros(spawn, write, tmp_path, "hang", "1s", *TASK)
    server.wait_for("running hang")
    shary.popen.send_signal(signal.SIGTERM)
    assert shary.exit_status(30) == 0, shary.lines
    shary._reader.join(5)
    assert "  navigate on /test/hang (r1): unconfirmed" in shary.lines
    states = [e.data["state"] for e in read_events(tmp_path / "log.sqlite", kind="ros-cancel")]
    assert states[-1] == "unconfirmed"


def _a_client_s_task_running(spawn, write, tmp_path):
    """A server whose goals run until cancelled, a plain ``~/run_task`` client, and
    ``shary ros``, with the client's task g1 running at the server."""
    server = spawn("tests/ros_servers.py", "long")
    client = spawn("tests/ros_client.py")
    server.wait_for("ready")
    client.wait_for("ready")
    shary = shary_ros(spawn, write, tmp_path)
    shary.wait_for("shary is node /shary on robot jido (stop); Ctrl-C stops it")
    client.send("goal g1 move-for-manipulate place=kitchen")
    server.wait_for("running long")
    return server, client, shary


def test_the_run_task_client_is_answered_when_shary_stops(spawn, write, tmp_path):
    server, client, shary = _a_client_s_task_running(spawn, write, tmp_path)
    shary.popen.send_signal(signal.SIGTERM)
    client.wait_for("result g1 ABORTED cancelled|shary stopped by SIGTERM")
    assert shary.exit_status(30) == 0
    assert executing(server, "long") == 0


def test_a_cancelled_run_task_goal_cancels_its_robot_goal(spawn, write, tmp_path):
    server, client, shary = _a_client_s_task_running(spawn, write, tmp_path)
    client.send("cancel g1")
    client.wait_for("result g1 CANCELED cancelled|cancelled by the client of ~/run_task")
    server.wait_for("canceled long")
    assert executing(server, "long") == 0
    shary.popen.send_signal(signal.SIGINT)
    assert shary.exit_status(30) == 0
    # the client was answered once the server had ended the robot's goal
    rows = [(e.kind, e.data) for e in read_events(tmp_path / "log.sqlite")
            if e.kind in ("ros-cancel", "run-task")]
    confirmed = rows.index(("ros-cancel", next(d for k, d in rows if k == "ros-cancel"
                                               and d["state"] == "confirmed")))
    answered = next(i for i, (k, d) in enumerate(rows) if d.get("verdict") == "cancelled")
    assert confirmed < answered, shary.lines


def test_closing_the_node_stops_the_supervisor_safely(write, ros_domain, spawn):
    """Node shutdown in-process (what ``shary run --ros`` does as it ends): the goal in
    flight is cancelled at the server before the node goes."""
    from shary.facts.database import FactDatabase
    from shary.io.recipes import load_library
    from shary.kernel.loop import EventLoop, WallClock
    from shary.kernel.supervisor import Supervisor
    from shary.log.told import Told
    from shary.ros.binding import load_binding
    from shary.ros.bridge import RosSupervision
    from shary.ros.node import RosNode

    server = spawn("tests/ros_servers.py", "long")
    binding = load_binding(write("binding.yaml", BINDING.replace("ACTION", "long")
                                 .replace("CANCEL", "3s")))
    loop = EventLoop(WallClock())
    events: list[tuple[str, str | None, dict]] = []
    fanout = Told()
    fanout.listeners.append(lambda time, kind, task, agent, data:
                            events.append((kind, task, data)))
    sup = Supervisor(load_library(), FactDatabase(), robot="jido", loop=loop, log=fanout)
    node = RosNode("shary", domain_id=ros_domain)
    ros = RosSupervision(sup, binding, node, fanout=fanout)
    try:
        sup.start_task("move-for-manipulate", {"place": "kitchen"})
        run_until(loop, lambda: "running long" in server.lines, 30)
    finally:
        node.close()
    assert ros.stopped is not None and ros.stopped.reason == "the node is shutting down"
    run_until(loop, lambda: executing(server, "long") == 0)
    assert "canceled long" in server.lines
    assert ("task-end", "n1", {"name": "move-for-manipulate", "outcome": "cancelled",
                               "reason": "the node is shutting down"}) in events


def test_concurrent_run_task_goals_never_share_a_server(spawn, write, tmp_path):
    """Fifteen ~/run_task goals at once, each a navigate then a look-at on one server: all
    are answered (rclpy's services would keep 10), and the server never ran two goals at
    once."""
    server = spawn("tests/ros_servers.py", "succeed")
    client = spawn("tests/ros_client.py")
    server.wait_for("ready")
    client.wait_for("ready")
    path = write("binding.yaml", "binding: one\nrobot: jido\ntasks:\n"
                 "  navigate: {action: /test/succeed, type: test_msgs/action/NestedMessage}\n"
                 "  look-at: {action: /test/succeed, type: test_msgs/action/NestedMessage}\n"
                 "  speak: {topic: /jido/say, type: std_msgs/msg/String, "
                 "goal: {data: \"{text}\"}}\n")
    shary = spawn("-m", "shary", "ros", str(path))
    shary.wait_for("shary is node /shary on robot jido (one); Ctrl-C stops it")
    for i in range(15):
        client.send(f"goal g{i} move-for-manipulate place=p{i}")
    end = time.monotonic() + 120
    while not all(any(line.startswith(f"result g{i} ") for line in client.lines)
                  for i in range(15)):
        assert time.monotonic() < end and shary.popen.poll() is None, client.lines
        time.sleep(0.05)
    executing = 0
    for line in server.lines:
        executing += {"running succeed": 1, "over succeed": -1}.get(line, 0)
        assert executing <= 1

"""``~/run_task``'s result says why: a plain rclpy client gets the verdict (done, failed,
declined, cancelled) with the reason the log holds, and SUCCEEDED only for done."""

from __future__ import annotations

import json

from rosfixtures import needs_ros, run_until
from test_ros_node import GIVE, heard, supervision
from test_ros_stop import shary_ros

pytestmark = needs_ros


def test_a_person_who_says_no_is_a_declined_verdict(write, ros_domain, spawn):
    client = spawn("tests/ros_client.py")
    robot = spawn("tests/ros_robot.py")
    loop, node, events = supervision(write, ros_domain)
    try:
        client.send(f"goal g1 {GIVE}")
        run_until(loop, lambda: "act n1 jido: ASK-TASK" in heard(client, "feedback", "g1"))
        robot.send("once /shary/person_act " + json.dumps({"agent": "alice",
                                                           "act": "H-DISAGREE"}))
        run_until(loop, lambda: heard(client, "result", "g1"))
        assert heard(client, "result", "g1") == ["ABORTED declined|alice said no"]
    finally:
        node.close()


def test_a_failed_robot_goal_is_the_reason_of_a_failed_verdict(spawn, write, tmp_path):
    server = spawn("tests/ros_servers.py", "abort")
    client = spawn("tests/ros_client.py")
    server.wait_for("ready")
    client.wait_for("ready")
    shary = shary_ros(spawn, write, tmp_path, "abort")
    shary.wait_for("shary is node /shary on robot jido (stop); Ctrl-C stops it")
    client.send("goal g1 move-for-manipulate place=kitchen")
    client.wait_for("result g1 ABORTED failed|aborted: /test/abort aborted the goal; it ended "
                    "in not-performed")


def test_a_robot_goal_whose_server_is_absent_says_so(spawn, write, tmp_path):
    client = spawn("tests/ros_client.py")
    client.wait_for("ready")
    path = write("binding.yaml", "binding: absent\nrobot: jido\ncodes: {kitchen: 5}\ntasks:\n"
                 "  navigate: {action: /test/nobody, type: test_msgs/action/NestedMessage}\n")
    shary = spawn("-m", "shary", "ros", str(path))
    shary.wait_for("shary is node /shary on robot jido (absent); Ctrl-C stops it")
    client.send("goal g1 move-for-manipulate place=kitchen")
    client.wait_for("result g1 ABORTED failed|server unavailable: no action server "
                    "/test/nobody (checked before sending); it ended in not-performed")

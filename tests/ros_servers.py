"""Real ROS 2 action servers for the tests, in a process of their own.

``python tests/ros_servers.py`` serves ``test_msgs/action/NestedMessage`` on
``/test/NAME`` for each behaviour below and prints, one line each, what
happens at the server (``ready``, ``clients`` once every action's client is
discovered, ``goal NAME CODE``, ``running NAME`` and ``over NAME`` as a goal's
execution begins and ends, ``cancel-requested NAME``, ``canceled NAME``), so a test can
see what reached it and that no goal is left executing.  The domain is
the environment's ``ROS_DOMAIN_ID`` (the test's own).

succeed         three feedbacks, then SUCCEEDED with bool_value true
fail-result     SUCCEEDED, but bool_value false and int32_value 7
abort           ABORTED with int32_value 7
reject          refuses every goal
slow-ack        accepts after 0.8 s, then runs until cancelled
long            accepts at once, runs until cancelled
hang            accepts, never ends, ignores cancels (accepting the request)
silent          never acknowledges
"""

from __future__ import annotations

import sys
import time

import rclpy
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from test_msgs.action import NestedMessage

BEHAVIOURS = ("succeed", "fail-result", "abort", "reject", "slow-ack", "long", "hang", "silent")


def say(*words: object) -> None:
    print(*words, flush=True)


def serve(node, name: str) -> ActionServer:
    def on_goal(request):
        say("goal", name, request.nested_field.int32_value)
        if name == "reject":
            return GoalResponse.REJECT
        if name == "slow-ack":
            time.sleep(0.8)
        while name == "silent" and rclpy.ok():
            time.sleep(0.05)
        return GoalResponse.ACCEPT

    def on_cancel(handle):
        say("cancel-requested", name)
        return CancelResponse.ACCEPT

    def execute(handle):
        say("running", name)
        try:
            return run(handle)
        finally:
            say("over", name)

    def run(handle):
        result = NestedMessage.Result()
        if name in ("succeed", "fail-result"):
            for i in range(3):
                feedback = NestedMessage.Feedback()
                feedback.nested_field.float64_value = (i + 1) / 3
                handle.publish_feedback(feedback)
                time.sleep(0.05)
            result.nested_field.bool_value = name == "succeed"
            result.nested_field.int32_value = 0 if name == "succeed" else 7
            handle.succeed()
            return result
        if name == "abort":
            result.nested_field.int32_value = 7
            handle.abort()
            return result
        while rclpy.ok():
            if handle.is_cancel_requested and name != "hang":
                handle.canceled()
                say("canceled", name)
                return result
            time.sleep(0.01)
        return result

    return ActionServer(node, NestedMessage, f"/test/{name.replace('-', '_')}",
                        execute_callback=execute, goal_callback=on_goal, cancel_callback=on_cancel,
                        callback_group=ReentrantCallbackGroup())


def main() -> None:
    names = sys.argv[1:] or BEHAVIOURS
    rclpy.init()
    node = rclpy.create_node("test_servers")
    servers = [serve(node, name) for name in names]
    executor = MultiThreadedExecutor(num_threads=len(servers) + 4)
    executor.add_node(node)
    say("ready")

    def clients() -> None:  # each action's client is discovered: its responses will arrive
        if all(node.count_subscribers(f"/test/{n.replace('-', '_')}/_action/feedback")
               for n in names):
            say("clients")
            timer.cancel()

    timer = node.create_timer(0.02, clients)
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    for server in servers:
        server.destroy()
    node.destroy_node()
    rclpy.try_shutdown()


if __name__ == "__main__":
    main()

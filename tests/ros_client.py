"""A plain rclpy client of shary's ``~/run_task`` for the tests, in a process of its own.

What any ROS 2 node would write: an ``ActionClient`` of
``shary_interfaces/action/RunTask`` on ``/shary/run_task``, nothing of shary
imported.  Reads commands on standard input, one a line: ``goal ID TASK
[NAME=VALUE ...]`` sends a goal, ``cancel ID`` cancels it.  Prints ``ready``,
then for each goal ``accepted ID`` or ``rejected ID``, ``feedback ID KIND NODE
TEXT`` as it comes, ``cancel ID CODE`` (the CancelGoal answer: 0 accepted) and
``result ID STATUS VERDICT|REASON`` (STATUS: SUCCEEDED, CANCELED, ABORTED).
Goals are sent and cancelled on the executor's thread (``create_task``), the
pattern the Jazzy wheel needs (docs/ros2.md).
"""

from __future__ import annotations

import sys
import threading

import rclpy
from action_msgs.msg import GoalStatus
from rclpy.action import ActionClient
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.qos import QoSProfile
from shary_interfaces.action import RunTask
from shary_interfaces.msg import Parameter

STATUS = {GoalStatus.STATUS_SUCCEEDED: "SUCCEEDED", GoalStatus.STATUS_CANCELED: "CANCELED",
          GoalStatus.STATUS_ABORTED: "ABORTED"}


def say(*words: object) -> None:
    print(*words, flush=True)


def main() -> None:
    rclpy.init()
    node = rclpy.create_node("test_client")
    deep = QoSProfile(depth=1000)  # the answers of many goals sent at once: none lost
    client = ActionClient(node, RunTask, "/shary/run_task", goal_service_qos_profile=deep,
                          result_service_qos_profile=deep, cancel_service_qos_profile=deep)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    handles: dict[str, object] = {}

    async def send(gid: str, goal: RunTask.Goal) -> None:
        def feedback(message) -> None:
            f = message.feedback
            say("feedback", gid, f.kind, f.node, f.text)

        handle = await client.send_goal_async(goal, feedback_callback=feedback)
        if not handle.accepted:
            say("rejected", gid)
            return
        handles[gid] = handle
        say("accepted", gid)
        answer = await handle.get_result_async()
        say("result", gid, STATUS.get(answer.status, answer.status),
            f"{answer.result.verdict}|{answer.result.reason}")

    async def cancel(gid: str) -> None:
        answer = await handles[gid].cancel_goal_async()
        say("cancel", gid, answer.return_code)

    def commands() -> None:
        for line in sys.stdin:
            word, gid, *rest = line.split()
            if word == "goal":
                if not client.wait_for_server(timeout_sec=30):
                    say("no server")
                    continue
                params = [Parameter(name=n, value=v)
                          for n, _, v in (item.partition("=") for item in rest[1:])]
                executor.create_task(send, gid, RunTask.Goal(task=rest[0], parameters=params))
            elif word == "cancel":
                executor.create_task(cancel, gid)
        rclpy.try_shutdown()

    threading.Thread(target=commands, daemon=True).start()
    say("ready")
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == "__main__":
    main()

"""shary's executors against real ROS 2 action servers in another process.

Every outcome of a goal (succeeded, aborted, canceled, rejected, server
unavailable, ack timeout, exec timeout), feedback as progress rows, cancel
before and after the acknowledgement (seen at the server), idempotent cancel,
and a server killed with SIGKILL mid-goal (noticed by shary's own deadline).
"""

from __future__ import annotations

import os
import signal
import time

import pytest
from rosfixtures import needs_ros, run_until

from shary.kernel.executors import Reporter, Request
from shary.kernel.loop import EventLoop, WallClock
from shary.ros.binding import load_binding

pytestmark = needs_ros

ATOMIC = {name: ("n",) for name in ("succeed", "fail-result", "abort", "reject", "slow-ack",
                                     "long", "hang", "silent", "absent", "absent-waited")}


def _binding(write):
    tasks = []
    for name in ATOMIC:
        server = {"absent": "0s", "absent-waited": "300ms"}.get(name, "20s")
        action = "/test/nobody" if name.startswith("absent") else f"/test/{name.replace('-', '_')}"
        tasks.append(f"""\
          {name}:
            action: {action}
            type: test_msgs/action/NestedMessage
            goal: {{nested_field.int32_value: "{{n}}"}}
            deadlines: {{server: {server}, ack: 5s, exec: 5s, cancel: 1s}}
            feedback: "{{nested_field.float64_value}} done"
            succeeded-if: {{nested_field.bool_value: true}}
            reason: "failure code {{nested_field.int32_value}}"
""")
    text = "binding: test\nrobot: robot\ntasks:\n" + "".join(tasks)
    return load_binding(write("binding.yaml", text.replace("\n          ", "\n  ")),
                        atomic=ATOMIC)


class Robot:
    """shary's side: a node, the executors, a wall-clock loop, the outcomes and the rows."""

    def __init__(self, binding, domain: int):
        from shary.ros.executors import RosExecutors
        from shary.ros.node import RosNode

        self.loop = EventLoop(WallClock())
        self.node = RosNode("shary_test", domain_id=domain)
        self.node.attach(self.loop)
        self.rows: list[tuple[str, dict]] = []
        self.executors = RosExecutors(self.node, binding, self.loop,
                                      record=lambda kind, **data: self.rows.append((kind, data)))
        self.outcomes: dict[str, object] = {}
        self.reporter = Reporter(lambda o: self.outcomes.setdefault(o.request.id, o),
                                 self.loop.call_soon)
        self._ids = 0

    def start(self, atomic: str, n: int = 1, priority: int = 2) -> Request:
        self._ids += 1
        request = Request(f"r{self._ids}", atomic, {"n": n}, "robot", f"node{self._ids}",
                          priority)
        self.executors.start(request, self.reporter)
        return request

    def outcome(self, request: Request, timeout: float = 30.0):
        run_until(self.loop, lambda: request.id in self.outcomes, timeout)
        return self.outcomes[request.id]

    def rows_of(self, kind: str, request: Request) -> list[dict]:
        return [d for k, d in self.rows if k == kind and d.get("request") == request.id]


@pytest.fixture
def robot(write, ros_domain):
    made = Robot(_binding(write), ros_domain)
    yield made
    made.node.close()
    assert made.loop.waiter is not made.node  # the loop sleeps on its own again


@pytest.fixture
def servers(robot, spawn):
    """The test servers, once they have discovered shary's clients (a response sent before
    that is lost: DDS discovery, not something shary can fix)."""
    process = spawn("tests/ros_servers.py")
    process.wait_for("clients")
    return process


def test_a_goal_succeeds_with_its_feedback_as_progress_rows(robot, servers):
    request = robot.start("succeed", 42)
    outcome = robot.outcome(request)
    assert outcome.status == "done", outcome.reason
    assert "goal succeed 42" in servers.lines  # the goal was built from the task's parameter
    assert [r["text"] for r in robot.rows_of("exec-progress", request)] == [
        "0.333 done", "0.667 done", "1 done"]
    assert robot.rows_of("ros-goal", request)[0]["outcome"] == "succeeded"


def test_aborted_rejected_and_failed_results_fail_with_the_reason(robot, servers):
    aborted, rejected, wrong = robot.start("abort"), robot.start("reject"), robot.start(
        "fail-result")
    assert robot.outcome(aborted).reason == "aborted: failure code 7"
    assert robot.outcome(rejected).reason == "rejected: /test/reject rejected the goal"
    assert robot.outcome(wrong).reason == "aborted: failure code 7"
    assert all(robot.outcomes[r.id].status == "failed" for r in (aborted, rejected, wrong))


def test_an_absent_server_fails_fast_or_after_its_deadline(robot):
    started = time.monotonic()
    at_once = robot.start("absent")
    assert robot.outcome(at_once).reason == (
        "server unavailable: no action server /test/nobody (checked before sending)")
    waited = robot.start("absent-waited")
    assert robot.outcome(waited).reason == (
        "server unavailable: no action server /test/nobody within 0.3 s")
    assert time.monotonic() - started < 5


def test_a_server_that_never_acknowledges_times_out_and_one_that_never_ends_too(robot,
                                                                                servers):
    silent, hang = robot.start("silent"), robot.start("hang")
    assert robot.outcome(silent).reason == (
        "ack timeout: /test/silent did not acknowledge the goal within 5 s")
    outcome = robot.outcome(hang)
    assert outcome.reason == "exec timeout: no result from /test/hang within 5 s"
    # the timed-out goal is cancelled at the server, which accepts but never ends it
    run_until(robot.loop, lambda: "cancel-requested hang" in servers.lines)
    run_until(robot.loop, lambda: any(r["state"] == "unconfirmed"
                                      for r in robot.rows_of("ros-cancel", hang)))


def test_cancel_reaches_the_server_and_is_idempotent(robot, servers):
    request = robot.start("long")
    run_until(robot.loop, lambda: "goal long 1" in servers.lines)
    run_until(robot.loop, lambda: robot.executors._goals[request.id].phase == "running")
    robot.executors.cancel(request)
    robot.executors.cancel(request)
    assert robot.outcome(request).status == "cancelled"
    run_until(robot.loop, lambda: "canceled long" in servers.lines)
    run_until(robot.loop, lambda: any(r["state"] == "confirmed"
                                      for r in robot.rows_of("ros-cancel", request)))
    assert servers.lines.count("cancel-requested long") == 1
    robot.executors.cancel(request)  # after the end too
    robot.loop.run_for(0.2)
    assert servers.lines.count("cancel-requested long") == 1


def test_a_goal_cancelled_before_its_acknowledgement_is_cancelled_once_acknowledged(
        robot, servers):
    request = robot.start("slow-ack")
    run_until(robot.loop, lambda: "goal slow-ack 1" in servers.lines)
    robot.executors.cancel(request)  # the server is still deciding (0.8 s)
    assert robot.outcome(request).status == "cancelled"
    # not left running at the server: no orphan
    run_until(robot.loop, lambda: "canceled slow-ack" in servers.lines)
    states = [r["state"] for r in robot.rows_of("ros-cancel", request)]
    run_until(robot.loop, lambda: "confirmed" in [
        r["state"] for r in robot.rows_of("ros-cancel", request)])
    assert states[0] == "sent after the acknowledgement"


def test_a_server_killed_mid_goal_is_noticed_by_shary_s_deadline(robot, spawn):
    server = spawn("tests/ros_servers.py", "long")
    server.wait_for("clients")
    request = robot.start("long")
    run_until(robot.loop, lambda: "goal long 1" in server.lines)
    os.kill(server.popen.pid, signal.SIGKILL)
    outcome = robot.outcome(request)  # DDS still sees the server for 20 s
    assert outcome.reason == "exec timeout: no result from /test/long within 5 s"
    run_until(robot.loop, lambda: any(r["state"] == "unconfirmed"
                                      for r in robot.rows_of("ros-cancel", request)))


def test_an_act_suspended_by_its_scheme_cancels_its_goal_at_the_server(write, ros_domain,
                                                                        spawn):
    """give-object-attentive: Alice looks away while the arm moves towards her (a ROS
    goal): WAIT-ATTENTION suspends REALIZE-TASK, the goal is cancelled at the server;
    she looks back, and the act resumes with a new goal."""
    from scripted import ScriptedExecutor

    from shary.facts.database import FactDatabase
    from shary.io.recipes import load_library
    from shary.kernel.executors import ExecutorRegistry
    from shary.kernel.supervisor import Supervisor
    from shary.ros.executors import RosExecutors
    from shary.ros.node import RosNode

    binding = load_binding(write("arm.yaml", """\
        binding: arm
        robot: jido
        codes: {alice: 30, bottle: 1}
        tasks:
          move-arm:
            action: /test/long
            type: test_msgs/action/NestedMessage
            goal: {nested_field.int32_value: "{code:target}"}
            deadlines: {server: 20s, exec: 60s}
        """))
    loop = EventLoop(WallClock())
    facts = FactDatabase()
    for triple in (("alice", "looksAt", "jido"), ("bottle", "isOn", "table"),
                   ("bottle", "isReachableBy", "jido")):
        facts.add(*triple)
    library = load_library()
    scripted = ScriptedExecutor(loop, durations=dict.fromkeys(library.atomic, 0.05))
    registry = ExecutorRegistry({name: scripted for name in library.atomic})
    node = RosNode("shary_sup", domain_id=ros_domain)
    try:
        node.attach(loop)
        RosExecutors(node, binding, loop).register(registry)
        server = spawn("tests/ros_servers.py", "long")
        server.wait_for("clients")
        sup = Supervisor(library, facts, robot="jido", loop=loop, executors=registry)
        sup.start_task("give-object", {"object": "bottle", "partner": "alice"})
        loop.run_until_idle()
        sup.receive_act("alice", "H-AGREE")
        run_until(loop, lambda: "goal long 30" in server.lines)
        facts.remove("alice", "looksAt", "jido")
        run_until(loop, lambda: "canceled long" in server.lines)
        facts.add("alice", "looksAt", "jido")
        run_until(loop, lambda: server.lines.count("goal long 30") == 2)
    finally:
        node.close()


def test_atomic_tasks_bound_to_one_action_share_its_client(write, ros_domain):
    """Each action client hears every status and feedback message of its action: one per
    action, or every goal would be handled as many times as tasks share it."""
    from shary.ros.executors import RosExecutors
    from shary.ros.node import RosNode

    binding = load_binding(write("shared.yaml", """\
        binding: shared
        robot: robot
        tasks:
          succeed: {action: /test/succeed, type: test_msgs/action/NestedMessage}
          abort: {action: /test/succeed, type: test_msgs/action/NestedMessage}
          long: {action: /test/long, type: test_msgs/action/NestedMessage}
        """), atomic=ATOMIC)
    with RosNode("shary_shared", domain_id=ros_domain) as node:
        RosExecutors(node, binding, EventLoop(WallClock()))
        assert len(node.waitables) == 2


def _one_at_a_time(lines: list[str], name: str) -> bool:
    """Whether the server never executed two goals of ``name`` at once."""
    executing = 0
    for line in lines:
        executing += {f"running {name}": 1, f"over {name}": -1}.get(line, 0)
        if executing > 1:
            return False
    return True


def test_a_second_goal_on_a_busy_server_waits_for_the_first_to_end_there(robot, servers):
    first, second = robot.start("long", 1), robot.start("long", 2)
    run_until(robot.loop, lambda: "running long" in servers.lines)
    robot.loop.run_for(0.5)
    assert "goal long 2" not in servers.lines
    [wait] = robot.rows_of("ros-resource", second)
    assert (wait["action"], wait["parts"], wait["holders"]) == (
        "wait", ["action /test/long"], ["r1"])
    robot.executors.cancel(first)
    run_until(robot.loop, lambda: "goal long 2" in servers.lines)
    # sent once the server had ended the first: never two goals on it
    assert servers.lines.index("canceled long") < servers.lines.index("goal long 2")
    robot.executors.cancel(second)
    assert robot.outcome(second).status == "cancelled"
    run_until(robot.loop, lambda: servers.lines.count("canceled long") == 2)
    assert _one_at_a_time(servers.lines, "long")


def test_a_goal_of_higher_priority_preempts_the_one_on_its_server(robot, servers):
    first = robot.start("long", 1)
    run_until(robot.loop, lambda: "running long" in servers.lines)
    urgent = robot.start("long", 2, priority=3)
    outcome = robot.outcome(first)
    assert outcome.status == "cancelled"
    assert outcome.reason == ("preempted: action /test/long needed by long of node2 "
                              "(priority 3 over 2)")
    run_until(robot.loop, lambda: "goal long 2" in servers.lines)
    assert servers.lines.index("canceled long") < servers.lines.index("goal long 2")
    assert [r["action"] for r in robot.rows_of("ros-resource", urgent)] == ["preempt", "serve"]
    robot.executors.cancel(urgent)
    run_until(robot.loop, lambda: servers.lines.count("canceled long") == 2)
    assert _one_at_a_time(servers.lines, "long")


def test_a_goal_cancelled_while_it_waits_is_never_sent(robot, servers):
    first, second = robot.start("long", 1), robot.start("long", 2)
    run_until(robot.loop, lambda: "running long" in servers.lines)
    robot.executors.cancel(second)
    assert robot.outcome(second).reason == ("cancelled before it was sent (it waited for "
                                            "action /test/long)")
    robot.executors.cancel(first)
    run_until(robot.loop, lambda: "canceled long" in servers.lines)
    robot.loop.run_for(0.3)
    assert "goal long 2" not in servers.lines


def test_tasks_sharing_a_part_of_the_robot_wait_for_each_other(write, ros_domain, spawn):
    """Two servers, one base: the second task's goal waits for the first's end."""
    from shary.ros.executors import RosExecutors
    from shary.ros.node import RosNode

    binding = load_binding(write("base.yaml", """\
        binding: base
        robot: robot
        tasks:
          long: {action: /test/long, type: test_msgs/action/NestedMessage, resources: [base]}
          succeed: {action: /test/succeed, type: test_msgs/action/NestedMessage,
                    resources: [base]}
        """), atomic=ATOMIC)
    loop = EventLoop(WallClock())
    outcomes: dict[str, object] = {}
    reporter = Reporter(lambda o: outcomes.setdefault(o.request.id, o), loop.call_soon)
    with RosNode("shary_base", domain_id=ros_domain) as node:
        node.attach(loop)
        executors = RosExecutors(node, binding, loop)
        server = spawn("tests/ros_servers.py", "long", "succeed")
        server.wait_for("clients")
        moving = Request("r1", "long", {}, "robot", "n1")
        executors.start(moving, reporter)
        run_until(loop, lambda: "running long" in server.lines)
        after = Request("r2", "succeed", {}, "robot", "n2")
        executors.start(after, reporter)
        loop.run_for(0.5)
        assert "running succeed" not in server.lines
        executors.cancel(moving)
        run_until(loop, lambda: "r2" in outcomes)
        assert outcomes["r2"].status == "done"
        assert server.lines.index("over long") < server.lines.index("running succeed")

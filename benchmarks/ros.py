"""shary's ROS 2 bridge against a bare rclpy client and its goals, in one run.

A child process (this script with ``--serve``) serves
``test_msgs/action/NestedMessage`` actions, ``/bench/instant`` (succeeds at
once; the same again as ``/bench/instant_bare`` and ``/bench/instant_crowded``,
one per client, so that no client hears the status messages of another's goals)
and ``/bench/long`` (runs until cancelled, printing when a cancel request
arrives, with its wall time), and publishes ``std_msgs/String`` perception
messages on request.  Against it, in this process:

- per-goal overhead: ``--goals`` sequential goals (send -> result) through a bare
  rclpy ``ActionClient`` (one node, a ``SingleThreadedExecutor`` in a thread, the
  goal sent with ``create_task``, the main thread waiting on an event) and through
  shary's :class:`~shary.ros.executors.RosExecutors` (request -> outcome on the
  engine's loop), alternated in blocks of 25; p50 and p99 of each, and the ratios
  (goal: within 1.25 x of bare);
- cancel latency: give-object-attentive with move-arm on ``/bench/long``: the time
  from removing "alice looksAt jido" from the facts to the cancel request reaching
  the server (the scheme suspends REALIZE-TASK, the act's goal is cancelled), over
  ``--cancels`` suspensions; p50, p99 (goal: p99 <= 50 ms);
- topic messages into facts: ``--messages`` messages published at a stated ``--rate``
  per second (not a flood: a publisher faster than the subscriber measures a backlog),
  each a line ``bench stamp TIME``; the messages that became facts, per second, and
  the time from publication to the fact (goal: >= 5,000 msg/s, p99 <= 5 ms).  Beside
  it, in the same run and at the same rate, the ceiling: a bare rclpy subscription on
  a node of its own with one callback per message (what rclpy's tutorials show), and
  one that drains the messages waiting with ``take_message`` (shary's way), each
  message's delay taken in its callback;
- a safe stop: ``shary ros`` started ``--stops`` times, each with a task whose navigate
  goal runs on ``/bench/stoppable``, then sent SIGTERM: the time from the signal to the
  cancel request reaching the server (the last robot goal cancelled), p50 and p99 (goal:
  p99 <= the binding's cancel deadline + 100 ms), and to the process's exit;
- one goal per resource: 20 concurrent ``~/run_task`` goals (explore-place and
  move-for-manipulate, each a navigate then a look-at) to a ``shary ros`` whose servers
  ``/bench/base`` and ``/bench/head`` would run several goals at once and count each goal
  that began while another ran (goal: 0), with the verdicts and the time all took.

    python benchmarks/ros.py [--json] [--goals 400] [--cancels 30] [--messages 20000]
                             [--stops 10]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent


INSTANT_PEERS = ("", "_bare", "_crowded")
"""The instant action once per client (shary's, the bare one's, the crowded one's): an
action's status messages carry every goal its server keeps (rclpy: for 15 minutes) and
every client of the action takes each of them, so clients that share an action slow
each other down, the more so the more of them spin beside the one measured."""
TOPICS = ("/bench/facts", "/bench/bare", "/bench/drained")
"""Perception topics: into shary's facts, to a bare rclpy subscription with one callback
per message, and to one that drains what waits with ``take_message``."""
DEPTH = 1000
"""The topics' history depth, at both ends (shary's perception subscribes with it)."""


def _pct(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


# -- the child: servers and a publisher -----------------------------------------------------


def serve() -> None:
    import rclpy
    from rclpy.action import ActionServer, CancelResponse
    from rclpy.callback_groups import ReentrantCallbackGroup
    from rclpy.executors import MultiThreadedExecutor
    from std_msgs.msg import String
    from test_msgs.action import NestedMessage

    rclpy.init()
    node = rclpy.create_node("bench_robot")
    group = ReentrantCallbackGroup()

    def instant(handle: Any) -> Any:
        handle.succeed()
        return NestedMessage.Result()

    def until_cancelled(said: str) -> Any:
        """A goal that runs until cancelled, printing ``said`` as it starts."""
        def execute(handle: Any) -> Any:
            print(said, flush=True)
            while rclpy.ok() and not handle.is_cancel_requested:
                time.sleep(0.002)
            if handle.is_cancel_requested:
                handle.canceled()
            else:  # shutting down
                handle.abort()
            return NestedMessage.Result()
        return execute

    def cancel_printing(said: str) -> Any:
        """A cancel request accepted, printing ``said`` and when it came."""
        def accept(handle: Any) -> Any:
            print(said, time.time(), flush=True)
            return CancelResponse.ACCEPT
        return accept

    long, cancel = until_cancelled("goal"), cancel_printing("cancel")
    stoppable, stop_cancel = until_cancelled("stop-goal"), cancel_printing("stop-cancel")

    running = {"base": 0, "head": 0}
    overlaps = {"base": 0, "head": 0}
    lock = threading.Lock()

    def busy(part: str) -> Any:
        def execute(handle: Any) -> Any:  # several goals may run at once: counted
            with lock:
                running[part] += 1
                overlaps[part] += running[part] > 1
            time.sleep(0.05)
            with lock:
                running[part] -= 1
            handle.succeed()
            return NestedMessage.Result()
        return execute

    servers = [*(ActionServer(node, NestedMessage, f"/bench/instant{peer}", instant,
                              callback_group=group) for peer in INSTANT_PEERS),
               ActionServer(node, NestedMessage, "/bench/long", long, cancel_callback=cancel,
                            callback_group=group),
               ActionServer(node, NestedMessage, "/bench/stoppable", stoppable,
                            cancel_callback=stop_cancel, callback_group=group),
               *(ActionServer(node, NestedMessage, f"/bench/{part}", busy(part),
                              callback_group=group) for part in running)]
    publishers = {topic: node.create_publisher(String, topic, DEPTH) for topic in TOPICS}

    def commands() -> None:
        for line in sys.stdin:
            words = line.split()
            if words and words[0] == "overlaps":
                with lock:
                    print("overlaps", overlaps["base"], overlaps["head"], flush=True)
            if words and words[0] == "publish":
                publisher, count, rate = publishers[words[1]], int(words[2]), float(words[3])
                while not publisher.get_subscription_count():
                    time.sleep(0.01)
                time.sleep(0.5)
                start = time.perf_counter()
                for i in range(count):
                    ahead = start + i / rate - time.perf_counter()
                    if ahead > 0:
                        time.sleep(ahead)
                    publisher.publish(String(data=f"bench stamp {time.time():.6f}"))
                print("published", words[1], time.perf_counter() - start, flush=True)
        rclpy.try_shutdown()

    threading.Thread(target=commands, daemon=True).start()
    executor = MultiThreadedExecutor(num_threads=8)
    executor.add_node(node)
    print("ready", flush=True)
    try:
        executor.spin()
    except Exception:  # noqa: BLE001 -- shutting down
        pass
    for server in servers:
        server.destroy()


class Child:
    def __init__(self) -> None:
        from shary.ros.env import ros_environment

        self.popen = subprocess.Popen([sys.executable, __file__, "--serve"], text=True,
                                      stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                      env=ros_environment())
        self.lines: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()
        self.wait(lambda: "ready" in self.lines)

    def _read(self) -> None:
        assert self.popen.stdout is not None
        for line in self.popen.stdout:
            self.lines.append(line.strip())

    def wait(self, condition: Any, timeout: float = 60.0, loop: Any = None) -> None:
        end = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > end:
                raise RuntimeError(f"the benchmark's robot did not answer: {self.lines[-5:]}")
            if loop is not None:
                loop.run_for(0.02)
            else:
                time.sleep(0.001)

    def send(self, line: str) -> None:
        assert self.popen.stdin is not None
        self.popen.stdin.write(line + "\n")
        self.popen.stdin.flush()

    def stop(self) -> None:
        """End the child; one that does not end on SIGTERM within 10 s (seen once on a
        loaded machine, its servers' threads still polling) is killed."""
        self.popen.terminate()
        try:
            self.popen.wait(10)
        except subprocess.TimeoutExpired:
            self.popen.kill()
            self.popen.wait()


# -- the measures ---------------------------------------------------------------------------


BINDING = """\
binding: bench
robot: jido
codes: {alice: 30, bottle: 1}
tasks:
  speak: {topic: /bench/say, type: std_msgs/msg/String, goal: {data: "{text}"}}
  move-arm: {action: /bench/long, type: test_msgs/action/NestedMessage,
             goal: {nested_field.int32_value: "{code:target}"}, deadlines: {server: 20s, ack: 10s}}
"""
FACTS = """\
facts:
  - {topic: /bench/facts, type: std_msgs/msg/String, lines: data}
"""
INSTANT = "  {name}: {{action: /bench/instant, type: test_msgs/action/NestedMessage, " \
          "deadlines: {{server: 20s, ack: 10s}}}}\n"


STOP_BINDING = """\
binding: stop
robot: jido
codes: {kitchen: 5}
tasks:
  navigate: {action: /bench/stoppable, type: test_msgs/action/NestedMessage,
             deadlines: {server: 20s, cancel: 2s}}
"""
STOP_DEADLINE = 2.0
"""The cancel deadline of the stop measure's binding (seconds)."""
SHARED_BINDING = """\
binding: shared
robot: jido
tasks:
  speak: {topic: /bench/say, type: std_msgs/msg/String, goal: {data: "{text}"}}
  navigate: {action: /bench/base, type: test_msgs/action/NestedMessage,
             deadlines: {server: 20s, ack: 10s}}
  look-at: {action: /bench/head, type: test_msgs/action/NestedMessage,
            deadlines: {server: 20s, ack: 10s}}
"""


def shary_ros(folder: str, binding: str, *more: str) -> subprocess.Popen:
    """``shary ros`` on ``binding`` (its text) as a process of its own."""
    from shary.ros.env import ros_environment

    path = Path(folder) / f"binding-{time.monotonic_ns()}.yaml"
    path.write_text(binding)
    return subprocess.Popen([sys.executable, "-m", "shary", "ros", str(path), *more],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env=ros_environment())


def stops(child: Child, count: int) -> dict[str, Any]:
    """SIGTERM to ``shary ros`` while its navigate goal runs: seconds to the cancel at the
    server, and to the process's exit."""
    import signal

    cancelled, exited = [], []
    with tempfile.TemporaryDirectory() as folder:
        for trial in range(count):
            process = shary_ros(folder, STOP_BINDING, "--task", "move-for-manipulate",
                                "--with", "place=kitchen")
            child.wait(lambda t=trial: child.lines.count("stop-goal") > t, timeout=60)
            signalled = time.time()
            process.send_signal(signal.SIGTERM)
            child.wait(lambda t=trial: sum(x.startswith("stop-cancel ") for x in child.lines)
                       > t, timeout=30)
            process.wait(30)
            exited.append(time.time() - signalled)
            said = [x for x in child.lines if x.startswith("stop-cancel ")][trial]
            cancelled.append(float(said.split()[1]) - signalled)
    return {"stops": count, "stop_cancel_p50_ms": statistics.median(cancelled) * 1000,
            "stop_cancel_p99_ms": _pct(cancelled, 0.99) * 1000,
            "stop_exit_p50_ms": statistics.median(exited) * 1000,
            "stop_deadline_ms": STOP_DEADLINE * 1000}


def shared(child: Child, goals: int = 20) -> dict[str, Any]:
    """``goals`` concurrent ~/run_task goals whose tasks use the base and the head: the
    goals that overlapped at a server, the verdicts, the time all took."""
    import rclpy
    from rclpy.action import ActionClient
    from shary_interfaces.action import RunTask
    from shary_interfaces.msg import Parameter

    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("bench_asker", context=context)
    deep = rclpy.qos.QoSProfile(depth=1000)  # the answers of goals sent at once: none lost
    client = ActionClient(node, RunTask, "/shary/run_task", goal_service_qos_profile=deep,
                          result_service_qos_profile=deep, cancel_service_qos_profile=deep)
    executor = rclpy.executors.SingleThreadedExecutor(context=context)
    executor.add_node(node)
    threading.Thread(target=executor.spin, daemon=True).start()
    verdicts: list[str] = []
    done = threading.Event()

    async def ask(i: int) -> None:
        task = ("explore-place", "move-for-manipulate")[i % 2]
        goal = RunTask.Goal(task=task, parameters=[Parameter(name="place", value=f"p{i}")])
        handle = await client.send_goal_async(goal)
        answer = await handle.get_result_async()
        verdicts.append(answer.result.verdict)
        if len(verdicts) == goals:
            done.set()

    with tempfile.TemporaryDirectory() as folder:
        process = shary_ros(folder, SHARED_BINDING)
        try:
            client.wait_for_server(timeout_sec=60)
            time.sleep(1.0)  # the servers discovered by shary too
            start = time.perf_counter()
            for i in range(goals):
                executor.create_task(ask, i)
            done.wait(120)
            took = time.perf_counter() - start
        finally:
            process.terminate()
            process.wait(30)
    child.send("overlaps")
    child.wait(lambda: any(x.startswith("overlaps ") for x in child.lines))
    base, head = map(int, [x for x in child.lines if x.startswith("overlaps ")][0].split()[1:])
    client.destroy()
    executor.shutdown()
    rclpy.try_shutdown(context=context)
    return {"shared_goals": goals, "shared_done": verdicts.count("done"),
            "shared_answered": len(verdicts), "shared_overlaps": base + head,
            "shared_seconds": took}


def measure(args: argparse.Namespace) -> dict[str, Any]:
    import rclpy
    from rclpy.action import ActionClient
    from std_msgs.msg import String
    from test_msgs.action import NestedMessage

    from shary.facts.database import FactDatabase
    from shary.io.recipes import load_library
    from shary.kernel.executors import ExecutorRegistry, Reporter, Request
    from shary.kernel.loop import EventLoop, WallClock
    from shary.kernel.supervisor import Supervisor
    from shary.log.told import Told
    from shary.ros.binding import load_binding
    from shary.ros.bridge import RosSupervision
    from shary.ros.node import RosNode

    os.environ.setdefault("ROS_DOMAIN_ID", str(50 + os.getpid() % 40))
    child = Child()
    library = load_library()
    text = BINDING + "".join(INSTANT.format(name=name) for name in library.atomic
                             if name not in ("speak", "move-arm", "say")) + FACTS
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "bench.yaml"
        path.write_text(text)
        binding = load_binding(path)
    loop, facts = EventLoop(WallClock()), FactDatabase()
    for triple in (("alice", "looksAt", "jido"), ("bottle", "isOn", "table"),
                   ("bottle", "isReachableBy", "jido")):
        facts.add(*triple)
    fanout = Told()
    sup = Supervisor(library, facts, robot="jido", loop=loop, log=fanout,
                     executors=ExecutorRegistry())
    node = RosNode("shary_bench")
    ros = RosSupervision(sup, binding, node, fanout=fanout)

    # the bare client: its own node and executor thread, as rclpy's documentation shows
    rclpy.init(args=None)
    bare_node = rclpy.create_node("bare_bench")
    bare_exec = rclpy.executors.SingleThreadedExecutor()
    bare_exec.add_node(bare_node)
    bare_client = ActionClient(bare_node, NestedMessage, "/bench/instant_bare")
    threading.Thread(target=bare_exec.spin, daemon=True).start()
    bare_client.wait_for_server(timeout_sec=30)
    # the peer's peer: a bare client on a node with as many action clients as shary's
    # (rclpy's executor walks every entity of its nodes each time it wakes)
    crowded_node = rclpy.create_node("crowded_bench")
    crowded_exec = rclpy.executors.SingleThreadedExecutor()
    crowded_exec.add_node(crowded_node)
    crowded_client = ActionClient(crowded_node, NestedMessage, "/bench/instant_crowded")
    extra = [ActionClient(crowded_node, NestedMessage, f"/bench/other{i}")
             for i in range(len(binding.tasks) - 1)]
    threading.Thread(target=crowded_exec.spin, daemon=True).start()
    crowded_client.wait_for_server(timeout_sec=30)

    def bare_goal(client: Any = bare_client, executor: Any = bare_exec) -> float:
        done = threading.Event()

        def send() -> None:
            future = client.send_goal_async(NestedMessage.Goal())
            future.add_done_callback(lambda f: f.result().get_result_async()
                                     .add_done_callback(lambda _: done.set()))

        start = time.perf_counter()
        executor.create_task(send)
        done.wait(10)
        return time.perf_counter() - start

    outcomes: dict[str, Any] = {}
    reporter = Reporter(lambda o: outcomes.__setitem__(o.request.id, (o, time.perf_counter())),
                        loop.call_soon)

    def shary_goal(i: int) -> float:
        request = Request(f"b{i}", "navigate", {"place": "x"}, "jido", f"n{i}")
        start = time.perf_counter()
        ros.executors.start(request, reporter)
        while request.id not in outcomes:
            loop.run_for(0.05)  # the time is taken when the outcome is delivered
        outcome, end = outcomes[request.id]
        if outcome.status != "done":
            raise RuntimeError(outcome.reason)
        return end - start

    loop.settle()  # the set-up above is long-lived: what a robot's main does (shary ros)
    for i in range(20):  # warm them up (discovery, first-goal costs)
        bare_goal()
        bare_goal(crowded_client, crowded_exec)
        shary_goal(-i - 1)
    bare, crowded, shary = [], [], []
    for block in range(0, args.goals, 25):
        bare += [bare_goal() for _ in range(25)]
        crowded += [bare_goal(crowded_client, crowded_exec) for _ in range(25)]
        shary += [shary_goal(block + i) for i in range(25)]

    # cancel latency: a fact change suspends the act, whose goal is cancelled
    sup.start_task("give-object", {"object": "bottle", "partner": "alice"})
    loop.run_until_idle()
    sup.receive_act("alice", "H-AGREE")
    cancels: list[float] = []
    for k in range(args.cancels):
        child.wait(lambda k=k: child.lines.count("goal") > k, loop=loop)
        loop.run_for(0.05)
        changed = time.time()
        facts.remove("alice", "looksAt", "jido")
        child.wait(lambda k=k: sum(1 for x in child.lines if x.startswith("cancel")) > k,
                   loop=loop)
        cancels.append(float([x for x in child.lines if x.startswith("cancel")][k].split()[1])
                       - changed)
        facts.add("alice", "looksAt", "jido")

    # topic messages: the bare peers first, then into shary's facts
    seen: dict[str, tuple[list[float], list[float]]] = {t: ([], []) for t in TOPICS}

    def heard(topic: str, stamp: str) -> None:
        now = time.time()
        seen[topic][0].append(now)
        seen[topic][1].append(now - float(stamp))

    topic_node = rclpy.create_node("bare_topics")
    topic_node.create_subscription(String, "/bench/bare",
                                   lambda m: heard("/bench/bare", m.data.split()[2]), DEPTH)
    drained: list[Any] = []

    def drain(message: Any) -> None:  # what rclpy users do: take the rest that waits
        with drained[0].handle:
            while message is not None:
                heard("/bench/drained", message.data.split()[2])
                got = drained[0].handle.take_message(String, False)
                message = got[0] if got else None

    drained.append(topic_node.create_subscription(String, "/bench/drained", drain, DEPTH))
    topic_exec = rclpy.executors.SingleThreadedExecutor()
    topic_exec.add_node(topic_node)
    threading.Thread(target=topic_exec.spin, daemon=True).start()
    facts.subscribe(lambda event: event.subject == "bench" and event.kind == "added"
                    and heard("/bench/facts", event.object))
    took: dict[str, float] = {}
    for topic in ("/bench/bare", "/bench/drained", "/bench/facts"):
        child.send(f"publish {topic} {args.messages} {args.rate}")
        child.wait(lambda t=topic: any(x.startswith(f"published {t} ") for x in child.lines),
                   timeout=120, loop=loop)
        took[topic] = float([x for x in child.lines if x.startswith(f"published {topic} ")][0]
                            .split()[2])
        loop.run_for(0.5)
    topic_exec.shutdown()
    node.close()
    stopped = stops(child, args.stops)
    sharing = shared(child)
    for client in (bare_client, crowded_client, *extra):
        client.destroy()
    bare_exec.shutdown()
    crowded_exec.shutdown()
    rclpy.try_shutdown()
    child.stop()
    ms = 1000.0

    def topic(topic: str, name: str) -> dict[str, Any]:
        arrived, delays = seen[topic]
        span = arrived[-1] - arrived[0] if len(arrived) > 1 else float("inf")
        return {f"{name}_received": len(arrived),
                f"{name}_msgs_per_s": (len(arrived) - 1) / span,
                f"{name}_p50_ms": statistics.median(delays) * ms if delays else float("inf"),
                f"{name}_p99_ms": _pct(delays, 0.99) * ms if delays else float("inf"),
                f"{name}_published_per_s": args.messages / took[topic]}

    return {
        "goals": args.goals, "bare_p50_ms": statistics.median(bare) * ms,
        "bare_p99_ms": _pct(bare, 0.99) * ms, "shary_p50_ms": statistics.median(shary) * ms,
        "shary_p99_ms": _pct(shary, 0.99) * ms, "action_clients": len(extra) + 1,
        "crowded_p50_ms": statistics.median(crowded) * ms,
        "crowded_p99_ms": _pct(crowded, 0.99) * ms,
        "ratio_p50": statistics.median(shary) / statistics.median(bare),
        "ratio_p99": _pct(shary, 0.99) / _pct(bare, 0.99),
        "cancels": len(cancels), "cancel_p50_ms": statistics.median(cancels) * ms,
        "cancel_p99_ms": _pct(cancels, 0.99) * ms,
        "messages_sent": args.messages, "topic_rate": args.rate,
        **topic("/bench/facts", "topic"), **topic("/bench/bare", "bare_topic"),
        **topic("/bench/drained", "drained_topic"), **stopped, **sharing,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    parser.add_argument("--goals", type=int, default=400)
    parser.add_argument("--cancels", type=int, default=30)
    parser.add_argument("--messages", type=int, default=20000)
    parser.add_argument("--rate", type=float, default=6000.0, help="messages per second")
    parser.add_argument("--stops", type=int, default=10, help="SIGTERMs of shary ros")
    parser.add_argument("--serve", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.serve:
        serve()
        return
    from shary.ros.env import reexec_with_libraries

    reexec_with_libraries()
    figures = measure(args)
    if args.json:
        print(json.dumps({k: round(v, 3) if isinstance(v, float) else v
                          for k, v in figures.items()}, indent=2))
        return
    print(f"goal round trip, {figures['goals']} goals: bare p50 {figures['bare_p50_ms']:.2f} ms "
          f"p99 {figures['bare_p99_ms']:.2f} ms; shary p50 {figures['shary_p50_ms']:.2f} ms "
          f"p99 {figures['shary_p99_ms']:.2f} ms; ratio p50 {figures['ratio_p50']:.2f} "
          f"p99 {figures['ratio_p99']:.2f} (goal <= 1.25); a bare client on a node with "
          f"{figures['action_clients']} action clients: p50 {figures['crowded_p50_ms']:.2f} ms "
          f"p99 {figures['crowded_p99_ms']:.2f} ms")
    print(f"fact change -> cancel at the server, {figures['cancels']} suspensions: "
          f"p50 {figures['cancel_p50_ms']:.1f} ms, p99 {figures['cancel_p99_ms']:.1f} ms "
          "(goal p99 <= 50 ms)")
    print(f"topic messages, {figures['messages_sent']} published at "
          f"{figures['topic_rate']:.0f}/s (goal into facts: >= 5,000 msg/s, p99 <= 5 ms):")
    for name, what in (("bare_topic", "bare rclpy, a callback per message"),
                       ("drained_topic", "bare rclpy, draining with take_message"),
                       ("topic", "shary, into facts")):
        print(f"  {what}: {figures[f'{name}_received']} received, "
              f"{figures[f'{name}_msgs_per_s']:.0f} msg/s (published at "
              f"{figures[f'{name}_published_per_s']:.0f}/s), p50 "
              f"{figures[f'{name}_p50_ms']:.2f} ms, p99 {figures[f'{name}_p99_ms']:.2f} ms")
    print(f"SIGTERM -> the robot's goal cancelled at the server, {figures['stops']} stops: "
          f"p50 {figures['stop_cancel_p50_ms']:.1f} ms, p99 {figures['stop_cancel_p99_ms']:.1f} "
          f"ms (goal p99 <= {figures['stop_deadline_ms'] + 100:.0f} ms, the cancel deadline + "
          f"100 ms); the process gone after p50 {figures['stop_exit_p50_ms']:.0f} ms")
    print(f"{figures['shared_goals']} concurrent ~/run_task goals over a base and a head: "
          f"{figures['shared_overlaps']} goals overlapping on a server (goal 0), "
          f"{figures['shared_done']} done of {figures['shared_answered']} answered, in "
          f"{figures['shared_seconds']:.1f} s")


if __name__ == "__main__":
    main()

"""shary's state for ROS tools stays bounded and readable however long shary runs:
/diagnostics once a second with the running tasks and the last ended, a bounded
snapshot, markers in the binding's frames, stamped, with a lifetime, deleted when over,
and the robot waiting for a person's attention shown above them."""

from __future__ import annotations

from rosfixtures import needs_ros, run_until

from shary.facts.database import FactDatabase
from shary.kernel.loop import EventLoop, WallClock
from shary.ros.binding import load_binding

pytestmark = needs_ros


def supervised(write, ros_domain, durations: float):
    """A supervisor on the wall clock with scripted executors (each action ``durations``
    seconds), its ROS supervision, and the loop."""
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
        frames: {robot: jido/base_footprint, person: "{agent}_head"}
        tasks:
          speak: {topic: /jido/say, type: std_msgs/msg/String, goal: {data: "{text}"}}
        """))
    loop, facts = EventLoop(WallClock()), FactDatabase()
    for triple in (("alice", "looksAt", "jido"), ("bottle", "isOn", "table"),
                   ("bottle", "isReachableBy", "jido"), ("alice", "type", "Human")):
        facts.add(*triple)
    library = load_library()
    scripted = ScriptedExecutor(loop, durations=dict.fromkeys(library.atomic, durations))
    fanout = Told()
    sup = Supervisor(library, facts, robot="jido", loop=loop, log=fanout,
                     executors=ExecutorRegistry({name: scripted for name in library.atomic}))
    node = RosNode("shary", domain_id=ros_domain)
    ros = RosSupervision(sup, binding, node, fanout=fanout)
    return loop, sup, ros, node


def test_views_stay_bounded_however_many_tasks_ended(write, ros_domain):
    from shary.ros.views import KEEP_ENDED, KEEP_ITEMS

    loop, sup, ros, node = supervised(write, ros_domain, 0.01)
    with node:
        for i in range(KEEP_ITEMS):  # each task: 4 or more acts and actions
            sup.start_task("explore-place", {"place": f"p{i}"})
        run_until(loop, lambda: not sup.runs)
        snapshot = ros.views.snapshot()
        assert len(snapshot["tasks"]) == KEEP_ENDED
        assert {t["outcome"] for t in snapshot["tasks"].values()} <= {"done", "failed"}
        kept = set(snapshot["tasks"])
        assert all(n["id"] in kept or n["parent"] is not None for n in snapshot["tree"])
        assert "n1" not in {n["id"] for n in snapshot["tree"]}  # the oldest forgotten
        statuses = ros.views.diagnostics().status
        assert len(statuses) == KEEP_ENDED + 1 and statuses[0].name == "shary"
        assert len(ros.views.view.items) <= 2 * KEEP_ITEMS
        assert statuses[0].message == "0 task(s) running; doing: nothing"


def test_markers_are_in_the_binding_s_frames_stamped_and_deleted_when_over(write,
                                                                            ros_domain):
    from shary.ros.views import MARKER_LIFETIME

    loop, sup, ros, node = supervised(write, ros_domain, 2.0)
    with node:
        sup.start_task("give-object", {"object": "bottle", "partner": "alice"})
        run_until(loop, lambda: ros.views.view.questions)
        markers = {m.ns: m for m in ros.views.markers().markers}
        robot, waiting = markers["shary/robot"], markers["shary/n1"]
        assert robot.header.frame_id == "jido/base_footprint"
        assert (waiting.header.frame_id, waiting.text) == ("alice_head", "waiting for alice")
        assert waiting.header.stamp.sec > 0 and waiting.lifetime.sec == MARKER_LIFETIME
        sup.receive_act("alice", "H-AGREE")
        run_until(loop, lambda: not ros.views.view.questions)
        gone = [m for m in ros.views.markers().markers if m.ns == "shary/n1"]
        assert [(m.action, m.id) for m in gone] == [(2, 0)]  # DELETE, as the question ended

        # she looks away while the robot acts: it waits for her attention
        run_until(loop, lambda: "realize" in ros.views.view.tasks["n1"]["config"])
        sup.facts.remove("alice", "looksAt", "jido")
        run_until(loop, lambda: any(m.text == "waiting for alice's attention"
                                    for m in ros.views.markers().markers))
        [shown] = [m for m in ros.views.markers().markers if m.ns == "shary/n1"]
        assert shown.header.frame_id == "alice_head" and shown.action == 0
        assert ros.views.diagnostics().status[1].level == bytes([1])  # WARN: waiting


def test_diagnostics_come_once_a_second_without_a_change(write, ros_domain, spawn):
    robot = spawn("tests/ros_robot.py", "/diagnostics=DiagnosticArray")
    robot.wait_for("ready")
    loop, sup, ros, node = supervised(write, ros_domain, 0.01)
    with node:
        run_until(loop, lambda: len([line for line in robot.lines
                                     if line.startswith("heard /diagnostics shary|0|")]) >= 3)


def test_with_use_sim_time_the_engine_and_the_stamps_follow_clock(ros_domain):
    """A simulation's /clock drives the engine's timers and the node's stamps; a stop runs
    on real time (a paused simulation would never let it end)."""
    import threading
    import time

    from rosgraph_msgs.msg import Clock

    from shary.ros.clock import RosClock
    from shary.ros.node import RosNode

    with RosNode("sim", domain_id=ros_domain) as sim, \
            RosNode("shary_sim", domain_id=ros_domain, use_sim_time=True) as node:
        publisher = sim.publisher(Clock, "/clock")
        running, paused = threading.Event(), threading.Event()
        running.set()

        def simulate() -> None:  # 50 ms of simulated time every 10 ms, until paused
            nanoseconds = 100 * 10**9
            while running.is_set():
                if not paused.is_set():
                    nanoseconds += 50_000_000
                message = Clock()
                message.clock.sec, message.clock.nanosec = divmod(nanoseconds, 10**9)
                publisher.publish(message)
                time.sleep(0.01)

        thread = threading.Thread(target=simulate, daemon=True)
        thread.start()
        try:
            loop = EventLoop(RosClock(node))
            node.attach(loop)
            node.spin_for(0.5)
            run_until(loop, lambda: loop.now() > 0)
            scheduled = node.node.get_clock().now().nanoseconds
            fired: list[int] = []
            loop.call_later(3.0, lambda: fired.append(node.node.get_clock().now().nanoseconds))
            run_until(loop, lambda: fired)
            assert fired[0] - scheduled >= 3 * 10**9  # three simulated seconds
            assert node.node.get_clock().now().to_msg().sec >= 103
            paused.set()
            loop.clock.follow_wall()
            before = loop.now()
            loop.run_for(0.1)  # the simulation is paused: real time runs on
            assert loop.now() >= before + 0.1
        finally:
            running.clear()
            thread.join(2)

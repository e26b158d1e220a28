"""A scenario with the robot reached only through ROS 2: both processes' commands.

``shary world --ros SCENARIO`` serves the scenario's living room as the
simulated Jido (:mod:`sim.rosworld`); ``shary run SCENARIO --ros`` runs the
supervisor in another process, on the wall clock, with the scenario's recipe
library, planner and goals, its ports filled by the Jido binding
(:class:`shary.ros.bridge.RosSupervision`): it waits for the robot's first
facts and its action servers, adds the goals, runs until nothing is left to
do, and judges the run against the scenario's expectations exactly as a run
in one process is judged (:func:`sim.run.happened`, :func:`sim.judge.judge`).
A world that dies mid-run (its liveliness lapses: :mod:`shary.ros.liveliness`)
fails the goals in flight at once and ends the run a second later, failed,
saying which node is gone, long before the scenario's timeout.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from shary.log.terminal import error, escape
from shary.log.terminal import out as _out

from .narration import Report
from .results import RunResult, tell_run

WAIT_FOR_ROBOT = 30.0
"""Wall seconds ``shary run --ros`` waits for the robot's facts and action servers."""
SETTLE = 1.0
"""Wall seconds with nothing left to do before the run is over (an answer on its way)."""


TEAM_SCENARIO = ("{}: a seam-welding scenario runs as a team over Zenoh ('shary team up', "
                 "docs/distributed.md), not behind ROS 2")


def _ros_ready() -> str | None:
    """Why ROS 2 cannot be used here, after restarting the program with the wheels'
    libraries found if it must."""
    from shary.ros.env import reexec_with_libraries, unavailable

    if Path(sys.argv[0]).name in ("shary", "__main__.py"):  # the program, not main() in-process
        reexec_with_libraries()
    return unavailable()


def cmd_world_ros(args: argparse.Namespace, path: Path) -> int:
    """``shary world --ros SCENARIO``: serve the living room for one run (until its
    supervisor leaves), Ctrl-C or --seconds."""
    from shary.ros.binding import load_binding
    from userfiles.errors import FileError

    from .narration import ConsoleReport
    from .scenario import is_team_scenario
    from .world import LivingRoom

    if is_team_scenario(path):
        return error(TEAM_SCENARIO.format(path.stem))
    problem = _ros_ready()
    if problem is not None:
        return error(problem)
    from shary.ros.node import RosNode

    from .rosworld import JIDO_BINDING, RosWorld

    try:
        binding = load_binding(JIDO_BINDING)
    except FileError as err:
        return error(str(err))
    stopping: list[int] = []
    previous = signal.signal(signal.SIGTERM, lambda *_: stopping.append(1))
    node = RosNode("jido_sim")
    try:
        with LivingRoom(gui=False, robot=None) as world:
            try:
                served = RosWorld(path, world, node, binding, seed=args.seed,
                                  report=None if args.quiet else ConsoleReport(_out))
            except ValueError as err:
                return error(str(err))
            name = served.scenario.name
            _out.print(f"the simulated {served.scenario.robot} of {name} is on ROS 2 "
                       f"({binding.name}), waiting for a supervisor ('shary run {name} "
                       "--ros'); it serves one run; Ctrl-C stops it")
            if served.serve(args.seconds, stopping, lambda: _out.print(
                    "a supervisor is there: the scenario starts")):
                _out.print(f"the supervisor left: this world served its run (for another, "
                           f"start 'shary world --ros {name}' again)")
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGTERM, previous)
        node.close()
    _out.print("the world stopped")
    return 0


def cmd_run_ros(args: argparse.Namespace, path: Path, out: Path, replacing: str | None) -> int:
    """``shary run SCENARIO --ros``: the supervisor of a scenario whose world is on ROS 2
    (with ``--world``, both started here as processes of their own).  It says what it
    waits for and, as the run goes, what happens (as a run in one process does), and
    writes the same folder: ``replacing`` says an earlier run's files are replaced."""
    from .narration import ConsoleReport
    from .scenario import is_team_scenario

    if is_team_scenario(path):
        return error(TEAM_SCENARIO.format(path.stem), json_mode=args.json)
    if args.world:
        return _with_world(args, path, out)
    problem = _ros_ready()
    if problem is not None:
        return error(problem, json_mode=args.json)
    from shary.ros.stop import sigterm_as_ctrl_c

    talk = not (args.quiet or args.json)
    if replacing and talk:
        _out.print(f"[dim]{escape(replacing)}[/dim]")
    with sigterm_as_ctrl_c():  # the node's closing stops the supervisor safely
        result = run_over_ros(path, out, wait=args.wait, seed=args.seed,
                              report=ConsoleReport(_out) if talk else None,
                              say=(lambda line: _out.print(f"[dim]{escape(line)}[/dim]"))
                              if talk else None)
    if isinstance(result, str):
        return error(result, json_mode=args.json, status=1)
    return tell_run(result, out, replacing, json_mode=args.json, quiet=args.quiet)


def _with_world(args: argparse.Namespace, path: Path, out: Path) -> int:
    """Start ``shary world --ros`` and ``shary run --ros`` as two processes that meet only
    on ROS 2, in a domain of their own unless ``ROS_DOMAIN_ID`` says which; the
    supervisor's exit status.  This process does not use ROS itself, so it needs no
    libraries found (a fresh shell, a test calling ``main``)."""
    from shary.ros.env import ros_environment
    from shary.ros.lifeline import die_with_parent, wait_passing_interrupts

    env = ros_environment()
    # both die with this process, even SIGKILLed; Ctrl-C reaches them through it, once each
    alone = {"preexec_fn": die_with_parent(), "start_new_session": True}
    env.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))
    shary = [sys.executable, "-m", "shary"]
    problems = tempfile.TemporaryFile("w+")  # what the world says only if it fails
    world = subprocess.Popen([*shary, "world", "--ros", str(path), "--quiet",
                              "--seed", str(args.seed)], env=env,
                             stdout=subprocess.DEVNULL, stderr=problems, text=True, **alone)
    if not (args.quiet or args.json):
        _out.print(f"[dim]the world runs in process {world.pid}, the supervisor in another, "
                   f"in ROS domain {env['ROS_DOMAIN_ID']}[/dim]")
    try:
        run = subprocess.Popen([*shary, "run", str(path), "--ros", "--out", str(out),
                                "--wait", str(args.wait), "--seed", str(args.seed),
                                *(["--json"] if args.json else []),
                                *(["--quiet"] if args.quiet else [])], env=env, **alone)
        wait_passing_interrupts(run)
    finally:
        world.send_signal(signal.SIGINT)
        try:
            world.wait(15)
        except subprocess.TimeoutExpired:
            world.kill()
            world.wait()
    with problems:
        problems.seek(0)
        said = problems.read().strip()
    if world.returncode not in (0, -signal.SIGINT) and said:
        _out.print(said, markup=False)
    return run.returncode


def run_over_ros(path: Path, out: Path, *, wait: float = WAIT_FOR_ROBOT, seed: int = 0,
                 report: Report | None = None,
                 say: Callable[[str], Any] | None = None) -> RunResult | str:
    """Run the scenario's supervisor against the robot on ROS 2 (see the module's
    docstring): the result, its files written to ``out`` as a run in one process writes
    them, or why it could not start.  ``report`` is told the story as it happens (times
    from the start of the run), ``say`` what the run waits for; ``seed`` is the world's,
    for the summary."""
    from std_msgs.msg import Bool, String

    from shary.dialogue.sessions import Sessions
    from shary.kernel.agenda import OVER, ChronicleRecognizer
    from shary.kernel.loop import EventLoop, WallClock
    from shary.kernel.planning import HatpPlanner
    from shary.kernel.supervisor import Supervisor
    from shary.log.contextlog import ContextLog, read_events
    from shary.log.told import Told
    from shary.recognition.models import load_action_models
    from shary.ros.binding import load_binding
    from shary.ros.bridge import RosSupervision
    from shary.ros.node import RosNode

    from .judge import judge
    from .narration import Narrator
    from .rosworld import JIDO_BINDING, QUIET, scenario_binding
    from .run import draw, fresh_folder, happened, load, write_summary
    from .stack.session import StackSession

    scenario, library, domain = load(path)
    binding = scenario_binding(load_binding(JIDO_BINDING), scenario)
    stack = StackSession(scenario.shared_plan, scenario.robot) if scenario.shared_plan else None
    log_path = fresh_folder(out)
    log = ContextLog(log_path, seed=seed)
    fanout = Told(log)
    loop = EventLoop(WallClock())
    from shary.facts.database import FactDatabase

    setup = time.perf_counter()
    start = loop.now()  # until the robot answers; then the run's start
    hatp = HatpPlanner(domain, budget_ms=300)
    if report is not None:
        told = report  # the story's times count from the run's start, as in one process
        narrator = Narrator(lambda t, who, kind, text: told(max(0.0, t - start), who, kind, text),
                            binding.robot, {p.name for p in scenario.people},
                            last_plan=lambda: hatp.last.plan if hatp.last else None,
                            robot_actions=True)
        fanout.listeners.append(lambda t, kind, task, agent, data:
                                narrator.event(t, kind, agent, data))
    facts = FactDatabase()
    sup = Supervisor(library, facts, robot=binding.robot, loop=loop, log=fanout,
                     planners={"living-room": hatp})
    if report is not None:
        sup.act_listeners.append(lambda run, state, agent: told(
            max(0.0, loop.now() - start), agent, "act", f"[{state.act}] {run.type.name}"))
    facts.log_changes(sup.record)
    node = RosNode("shary")
    try:
        ros = RosSupervision(sup, binding, node, fanout=fanout)
        plan_pub = node.publisher(String, "~/plan", depth=100) if stack else None
        world_quiet = [False]
        node.subscription(Bool, QUIET, lambda m: node.put(world_quiet.__setitem__, 0, m.data))
        listeners = [p for p in (ros.server.acts_pub, plan_pub) if p is not None]

        def ready() -> bool:  # the robot's servers found, the world's people listening
            return ros.executors.ready() and all(p.get_subscription_count() for p in listeners)

        if say is not None:
            say(f"waiting for the robot on ROS 2 (domain {os.environ.get('ROS_DOMAIN_ID', '0')}):"
                f" its facts on {binding.facts[0].topic} and its action servers, at most "
                f"{wait:g} s")
        deadline = time.monotonic() + wait
        while not (ros.perception.messages and ready()):
            if time.monotonic() > deadline:
                return (f"no simulated robot answered on ROS 2 within {wait:g} s (its facts on "
                        f"{binding.facts[0].topic}, its action servers): start it with "
                        f"'shary world --ros {scenario.name}' in the same ROS domain")
            loop.run_for(0.1)
        loop.settle()  # set up: a collection of the whole heap would stall perception
        if say is not None:
            say(f"the robot answered after {loop.now() - start:.1f} s: running "
                f"{scenario.name}")
        start = loop.now()
        setup = time.perf_counter() - setup
        wall = time.perf_counter()
        for goal in scenario.goals:
            loop.call_later(goal.at, lambda g=goal: sup.agenda.add(g.task, g.args,
                                                                   priority=g.priority))
        chronicles = ChronicleRecognizer(sup) if library.chronicles else None
        sessions = Sessions(sup)
        sessions.start()
        if scenario.action_models:  # what is there at the start was not done by anyone
            sup.recognize(load_action_models(scenario.action_models, facts,
                                             atomic=library.atomic))
        if stack is not None and plan_pub is not None:
            follower = stack.follow(sup, scenario.shared_plan["decision-wait"])
            follower.watchers.append(lambda event, task: plan_pub.publish(
                String(data=json.dumps(
                    {"event": event, "task": task, "current": follower.current,
                     "finished": follower.finished,
                     "labels": {t: p.label() for t, p in follower.plan.primitive.items()}}))))
            follower.start()
        quiet_since = gone_since = None
        end = start + scenario.timeout
        while loop.now() < end:
            loop.run_for(0.1)
            if ros.liveliness.gone:  # the robot's node is gone: its goals failed at once
                if gone_since is None:
                    gone_since = loop.now()
                if loop.now() - gone_since >= SETTLE:  # what the failures do, logged
                    break
                continue
            gone_since = None  # back before the run ended
            quiet = (not sup.runs and sup.agenda.active is None
                     and all(g.state in OVER for g in sup.agenda.goals)
                     and loop.now() - start > max((g.at for g in scenario.goals), default=0)
                     and not (stack is not None and stack.busy) and world_quiet[0]
                     and not sessions.timing
                     and not (chronicles is not None and chronicles.timing))
            quiet_since = (quiet_since or loop.now()) if quiet else None
            if quiet_since is not None and loop.now() - quiet_since >= SETTLE:
                break
        elapsed = loop.now() - start
        wall = time.perf_counter() - wall
        sup.record("run-end", scenario=scenario.name)
    finally:
        node.close()
    log.flush()
    events = [(e.time - start, e.kind, e.task, e.agent, e.data) for e in read_events(log_path)]
    log.close()
    differences = judge(scenario.expect, happened(events, facts, binding.robot, elapsed))
    if gone_since is not None and ros.liveliness.gone:
        differences += [f"{reason}: the run ended at {gone_since - start:.1f} s"
                        for reason in ros.liveliness.gone]
    elif elapsed >= scenario.timeout - 1e-9:
        differences.append(f"the run was still going at the timeout ({scenario.timeout:g}s)")
    result = RunResult(scenario.name, not differences, differences, elapsed, wall, setup, seed,
                       physics_steps=None, noise_misses=None, over="ros2")
    result.outputs = draw(sup.tree, log_path, out, scenario.name)
    write_summary(result, out)
    return result

"""``shary ros BINDING``: run the supervisor on a robot, reaching it only through ROS 2.

The supervisor runs on the wall clock with the built-in recipe library; its
executors, perception and speech are the binding's (:mod:`shary.ros.bridge`);
other nodes ask it for tasks over ``~/run_task`` and it shows its state on
``~/snapshot``, ``~/active_state``, ``/diagnostics`` and ``~/markers``
(docs/ros2.md).  ``--task`` starts one task at once; ``--facts`` loads what
the robot knows beforehand (a Turtle file: places' positions, kinds of
things); ``--use-sim-time`` runs the engine on the simulation's ``/clock``
(:mod:`shary.ros.clock`).  Ctrl-C (or SIGTERM) stops it safely (:mod:`shary.ros.stop`): every task
cancelled, every robot goal cancelled and its server's answer awaited up to the goal's
``cancel`` deadline, every ``~/run_task`` goal answered, then the node's entities
destroyed and the log written; a second Ctrl-C abandons the wait and says which goals it
left (exit status 1).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from shary.log.terminal import EXIT_BAD_INPUT, error, print_problems
from shary.log.terminal import out as _out


def add_ros(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("ros", help="run the supervisor on a ROS 2 robot described by a "
                       "binding file (pip install '.[ros]')",
                       description="Run the supervisor as a ROS 2 node: the binding's actions, "
                       "services and topics perform atomic tasks and bring facts and speech; "
                       "other nodes ask for tasks on ~/run_task.")
    p.add_argument("binding", type=Path, metavar="BINDING",
                   help="a robot binding (.yaml); or 'interfaces SRC…': build the robot's ROS 2 "
                   "interface packages from their source folders into this environment")
    p.add_argument("sources", nargs="*", type=Path, metavar="SRC", help=argparse.SUPPRESS)
    p.add_argument("--task", metavar="NAME", help="start this task at once")
    p.add_argument("--with", dest="params", action="append", default=[], metavar="PARAM=VALUE",
                   help="a parameter of --task (repeat for each)")
    p.add_argument("--facts", type=Path, metavar="FILE.ttl",
                   help="what the robot knows beforehand (Turtle)")
    p.add_argument("--log", type=Path, metavar="LOG.sqlite", help="write the context log here")
    p.add_argument("--seconds", type=_seconds, metavar="S",
                   help="stop after S seconds (default: run until Ctrl-C)")
    p.add_argument("--node-name", default="shary", metavar="NAME", help="the node's name")
    p.add_argument("--use-sim-time", action="store_true",
                   help="run on the simulation's time (/clock), as the robot's nodes do with "
                   "use_sim_time")
    p.set_defaults(func=cmd_ros)


def _seconds(text: str) -> float:
    """A duration of at least 0 s (argparse's type: its error is a clean one)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"{text!r}: a duration is 0 s or more")
    return value


def cmd_interfaces(sources: list[Path]) -> int:
    """``shary ros interfaces SRC…`` (:mod:`shary.ros.interfaces`)."""
    from shary.ros.interfaces import build
    from userfiles.errors import FileError

    if not sources:
        return error("shary ros interfaces SRC…: name the source folder of each interface "
                     "package (package.xml and msg/, srv/, action/)")
    try:
        built = build(sources, say=lambda text: _out.print(text, markup=False))
    except FileError as err:
        print_problems(err.problems)
        return EXIT_BAD_INPUT
    except RuntimeError as err:
        return error(str(err), status=1)
    _out.print(f"built and installed: {', '.join(built)}")
    return 0


def cmd_ros(args: argparse.Namespace) -> int:
    from shary.facts.database import FactDatabase
    from shary.io.recipes import load_library
    from shary.kernel.loop import EventLoop, WallClock
    from shary.kernel.planning import planners_for
    from shary.kernel.supervisor import Supervisor
    from shary.log.contextlog import ContextLog
    from shary.log.told import Told
    from shary.ros.binding import load_binding
    from shary.ros.bridge import RosSupervision
    from shary.ros.clock import RosClock
    from shary.ros.node import RosNode
    from shary.ros.stop import StopSignals
    from userfiles.errors import FileError

    if str(args.binding) == "interfaces" and not args.binding.is_file():
        return cmd_interfaces(args.sources)
    if args.sources:
        return error(f"unexpected {' '.join(map(str, args.sources))}: shary ros takes one "
                     "binding")
    params: dict[str, Any] = {}
    for item in args.params:
        key, sep, value = item.partition("=")
        if not sep or not key:
            return error(f"--with {item!r}: write PARAM=VALUE")
        params[key] = value
    if params and args.task is None:
        return error("--with gives a parameter of --task, which is not given")
    if args.log is not None and args.log.exists():
        return error(f"{args.log}: the file exists (the context log is written to a new "
                     "file: remove it or name another)")
    try:
        binding = load_binding(args.binding)
        facts = FactDatabase()
        if args.facts is not None:
            facts.load_turtle(args.facts)
    except FileError as err:
        print_problems(err.problems)
        return EXIT_BAD_INPUT
    from shary.ros.env import reexec_with_libraries, unavailable

    if Path(sys.argv[0]).name in ("shary", "__main__.py"):  # the program, not main() in-process
        reexec_with_libraries()
    problem = unavailable()
    if problem is not None:
        return error(problem)
    from rclpy.exceptions import InvalidNodeNameException
    from rclpy.validate_node_name import validate_node_name

    try:
        validate_node_name(args.node_name)
    except InvalidNodeNameException:
        return error(f"--node-name {args.node_name!r} is not a ROS node name (letters, digits "
                     "and _, not starting with a digit)")
    library = load_library()
    try:
        planners = planners_for(library)
    except FileError as err:
        print_problems(err.problems)
        return EXIT_BAD_INPUT
    for note in binding.notes:  # a type not installed here: its tasks fail at once
        _out.print(f"{note.file}:{note.line}:{note.col}: warning: {note.message}; its tasks "
                   "fail at once (server unavailable)", markup=False)
    if args.task is not None:
        task = library.tasks.get(args.task)
        if task is None:
            return error(f"no task {args.task!r} (known: {', '.join(sorted(library.tasks))})")
        missing = [p for p in task.params if p not in params]
        unknown = [p for p in params if p not in task.params]
        if missing or unknown:
            return error(f"--task {args.task} takes {', '.join(task.params) or 'nothing'} "
                         f"(--with PARAM=VALUE each)"
                         + (f"; missing: {', '.join(missing)}" if missing else "")
                         + (f"; unknown: {', '.join(unknown)}" if unknown else ""))
    log = ContextLog(args.log) if args.log is not None else None
    fanout = Told(log)
    node = RosNode(args.node_name, use_sim_time=args.use_sim_time)
    loop = EventLoop(RosClock(node) if args.use_sim_time else WallClock())
    sup = Supervisor(library, facts, robot=binding.robot, loop=loop, log=fanout,
                     planners=planners)
    facts.log_changes(sup.record)
    ros = None
    failed = None
    with StopSignals(loop) as signals:
        try:
            ros = RosSupervision(sup, binding, node, fanout=fanout)
            ros.liveliness.watchers.append(lambda reason: _out.print(
                f"{reason}: its tasks fail until it is back", markup=False))
            ros.qos.watchers.append(lambda text: _out.print(f"warning: {text}", markup=False))
            loop.settle()  # set up: a collection of the whole heap would stall perception
            _out.print(f"shary is node /{args.node_name} on robot {binding.robot} "
                       f"({binding.name}); Ctrl-C stops it")
            if args.task is not None:
                try:
                    sup.start_task(args.task, params)
                except (KeyError, ValueError, LookupError) as err:
                    failed = f"--task {args.task} cannot start: {err}"
            end = loop.now() + args.seconds if args.seconds is not None else None
            while failed is None and signals.requested is None and (end is None
                                                                    or loop.now() < end):
                loop.run_for(0.1)
            if ros is not None:
                ros.stop_reason = (f"shary stopped by {signals.requested}" if signals.requested
                                   else f"shary stopped after {args.seconds:g} s")
        finally:
            node.close()  # stops safely first (shary.ros.stop)
            if log is not None:
                log.flush()
                log.close()
    left = False
    stopped = ros.stopped if ros is not None else None
    if stopped is not None and (stopped.tasks or stopped.cancelled or stopped.left):
        for line in stopped.lines():
            _out.print(line, markup=False)
        left = bool(stopped.left)
    _out.print("shary stopped")
    if failed is not None:
        return error(failed)
    return 1 if left else 0

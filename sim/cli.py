"""The simulator's ``shary`` commands: ``run`` and ``scenarios``.

They are registered as entry points of the group ``shary.commands``
(:mod:`shary.cli`), so the engine offers them when this package is installed
and never imports it.  PyBullet is imported only when a scenario runs.
"""

from __future__ import annotations

import argparse
import re
import shlex
from pathlib import Path
from typing import Any

from shary.log.terminal import add_json_flag, emit_json, error, escape, listing
from shary.log.terminal import out as _out
from userfiles import yamlsafe
from userfiles.errors import FileError
from userfiles.schema import did_you_mean

from .results import earlier_run, tell_run, wrote


def add_scenarios(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("scenarios", help="list the built-in scenarios")
    add_json_flag(p, "the list")
    p.set_defaults(func=cmd_scenarios)


def cmd_scenarios(args: argparse.Namespace) -> int:
    from sim.scenario import builtin_scenarios, load_scenario

    return listing("scenarios", [(name, load_scenario(path).doc, path)
                                 for name, path in builtin_scenarios().items()],
                   json_mode=args.json)


def add_run(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="run a scenario on the simulated Jido (headless), judge it")
    p.add_argument("scenario", metavar="NAME|FILE",
                   help="a built-in scenario (see 'shary scenarios') or a scenario file")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the people's random choices (default 0)")
    p.add_argument("--gui", action="store_true", help="open PyBullet's window")
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="where to write log.sqlite, tree.svg, timeline.svg, summary.json "
                   "(default: runs/SCENARIO, after the scenario's name)")
    p.add_argument("--snapshots", action="store_true", help="also write PNG views at each act")
    p.add_argument("--quiet", action="store_true",
                   help="print only the verdict (and, when it failed, why)")
    p.add_argument("--ros", action="store_true",
                   help="run only the supervisor, reaching the robot through ROS 2: the world "
                   "runs in another process ('shary world --ros SCENARIO')")
    p.add_argument("--world", action="store_true",
                   help="with --ros: start the world too ('shary world --ros SCENARIO'), as a "
                   "process of its own, in a ROS domain of its own unless ROS_DOMAIN_ID is set")
    p.add_argument("--wait", type=float, default=30.0, metavar="S",
                   help="with --ros: how long to wait for the robot (default 30 s)")
    add_json_flag(p, "the verdict, the figures and the files written (no progress lines)")
    p.set_defaults(func=cmd_run)


_NAME = re.compile(r"^[A-Za-z0-9_-]+$")


def _name_of(path: Path) -> str:
    """The scenario's name, for the default output folder (``runs/NAME``).

    Only the ``scenario:`` key is read here; :func:`sim.run.run_scenario` checks
    the whole file (and refuses it, before writing anything, if the name is bad).
    """
    try:
        name = yamlsafe.load_file(path).data.get("scenario")
    except (FileError, AttributeError):
        name = None
    return name if isinstance(name, str) and _NAME.match(name) else path.stem


def cmd_run(args: argparse.Namespace) -> int:
    from sim.narration import ConsoleReport
    from sim.run import run_scenario
    from sim.scenario import find_scenario

    try:
        path = find_scenario(args.scenario)
    except KeyError as err:
        return error(err.args[0], json_mode=args.json)
    out = args.out or Path("runs") / _name_of(path)
    replacing = earlier_run(out)
    if args.ros:
        from sim.rosrun import cmd_run_ros

        return cmd_run_ros(args, path, out, replacing)
    if replacing and not (args.quiet or args.json):
        _out.print(f"[dim]{escape(replacing)}[/dim]")
    try:
        result = run_scenario(path, seed=args.seed, out=out, snapshots=args.snapshots,
                              gui=args.gui,
                              report=None if args.quiet or args.json else ConsoleReport(_out))
    except RuntimeError as err:
        return error(str(err), json_mode=args.json, status=1)
    return tell_run(result, out, replacing, json_mode=args.json, quiet=args.quiet)


def add_serve(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("serve", help="watch and steer a scenario, or replay a log, in the "
                       "browser (the operator console)")
    p.add_argument("scenario", nargs="?", metavar="NAME|FILE",
                   help="a built-in scenario (see 'shary scenarios') or a scenario file, "
                   "run live when the first page connects (weld-…: a team on its site)")
    p.add_argument("--team", type=Path, metavar="TEAM.yaml",
                   help="run a team file alone instead (people and software agents; "
                   "robots need a seam-welding scenario's site)")
    p.add_argument("--replay", type=Path, metavar="LOG",
                   help="replay a recorded run (its log.sqlite) with a time slider instead")
    p.add_argument("--host", default="127.0.0.1", metavar="ADDR",
                   help="the address to listen on (default 127.0.0.1: this machine only)")
    p.add_argument("--port", type=int, default=8765, metavar="N", help="default 8765")
    p.add_argument("--speed", type=float, default=1.0, metavar="X",
                   help="simulated seconds per wall second (default 1; 0: as fast as possible)")
    p.add_argument("--paused", action="store_true",
                   help="pause the run after its first step (set breakpoints, then Resume)")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the people's random choices (default 0)")
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="where the live run writes its files (default: runs/SCENARIO)")
    p.add_argument("--snapshots", action="store_true",
                   help="also write PNG views at each act (shown with the robot's questions)")
    p.set_defaults(func=cmd_serve)


def cmd_serve(args: argparse.Namespace) -> int:
    from shary.console.server import serve

    if [args.scenario, args.replay, args.team].count(None) != 2:
        return error("give a scenario to run, --team TEAM.yaml or --replay LOG (one of them)")
    if not 0 < args.port < 65536:
        return error(f"--port {args.port}: a port is a number from 1 to 65535")
    if not 0 <= args.speed <= 1000:
        return error(f"--speed {args.speed:g}: from 0 (as fast as possible) to 1000")
    if args.replay is not None:
        from shary.console.replay import Replay, named_schemes

        return serve(Replay(args.replay, named_schemes()), args.host, args.port)
    if args.team is not None:
        live = team_run(args.team, out=args.out, seed=args.seed, speed=args.speed,
                        paused=args.paused)
        return live if isinstance(live, int) else _serve_live(live, args.host, args.port)
    from sim.scenario import find_scenario

    try:
        path = find_scenario(args.scenario)
    except KeyError as err:
        return error(err.args[0])
    live = live_run(path, out=args.out, seed=args.seed, snapshots=args.snapshots,
                    speed=args.speed, paused=args.paused)
    return _serve_live(live, args.host, args.port)


def _serve_live(live: Any, host: str, port: int) -> int:
    """Serve a live run, first saying whether it will replace an earlier run's files; say
    its verdict and the files it wrote when it ends (the server goes on, for the page),
    or, when the server stops first, that it did not end."""
    from shary.console.server import serve

    replacing = earlier_run(live.folder) if live.folder is not None else None
    if replacing:
        _out.print(escape(replacing))

    def ended(summary: dict[str, Any]) -> None:
        verdict = "[bold green]PASSED[/bold green]" if summary.get("passed") else \
            "[bold red]FAILED[/bold red]"
        _out.print(f"{verdict} {escape(live.title)}: "
                   f"{summary['simulated_seconds']:.1f} s simulated")
        for difference in summary["differences"]:
            _out.print(f"  - {escape(difference)}")
        _out.print(wrote(live.folder, summary["outputs"]))

    live.ended = ended
    status = serve(live, host, port)
    if live.state == "ended" and live.summary is None:
        _out.print(f"[dim]the run was stopped before its end: {escape(str(live.folder))}/ "
                   "holds its log so far[/dim]")
    return status


def live_run(path: Path, *, out: Path | None = None, seed: int = 0, snapshots: bool = False,
             speed: float = 1.0, paused: bool = False) -> Any:
    """A :class:`shary.console.live.LiveRun` of a scenario file (read and checked now; run
    when the first page connects), writing its files to ``out`` (default runs/SCENARIO)."""
    from shary.console.live import LiveRun
    from shary.console.replay import named_schemes
    from sim.run import load, run_scenario
    from sim.scenario import is_team_scenario

    if is_team_scenario(path):
        return _weld_run(path, out=out, seed=seed, snapshots=snapshots, speed=speed,
                         paused=paused)
    scenario, library, _ = load(path)  # a bad file is refused here, before serving
    schemes = {choice.scheme.name: choice.scheme for task in library.tasks.values()
               for choice in task.schemes}
    out = out or Path("runs") / _name_of(path)
    builtin = named_schemes()  # the schemes the engine runs besides the tasks' (a plan's)
    return LiveRun(scenario.name, lambda attachment: run_scenario(
        path, seed=seed, out=out, snapshots=snapshots, console=attachment),
        out, schemes=lambda name: schemes.get(name) or builtin(name), speed=speed,
        paused=paused)


def _weld_run(path: Path, *, out: Path | None, seed: int, snapshots: bool, speed: float,
              paused: bool) -> Any:
    """A team on the seam-welding site, live (:func:`sim.weld.run.run_weld` with the console)."""
    from shary.console.live import LiveRun
    from shary.console.teamlive import TeamSteering
    from shary.team.teamfile import robot_library
    from sim.weld.run import run_weld
    from sim.weld.scenario import load_weld_scenario

    scenario = load_weld_scenario(path)  # a bad file is refused here, before serving
    library = robot_library(scenario.team)
    schemes = {choice.scheme.name: choice.scheme for task in library.tasks.values()
               for choice in task.schemes}
    out = out or Path("runs") / _name_of(path)
    return LiveRun(scenario.name, lambda attachment: run_weld(
        path, seed=seed, out=out, snapshots=snapshots, console=attachment),
        out, schemes=schemes.get, speed=speed, paused=paused, steering=TeamSteering())


def team_run(path: Path, *, out: Path | None = None, seed: int = 0, speed: float = 1.0,
             paused: bool = False) -> Any:
    """A team file run alone under the console (people and software agents), or the exit
    status of a refusal: a team with robots needs a world."""
    from shary.console.live import LiveRun
    from shary.console.teamlive import TeamSteering, refuse_robots, run_team
    from shary.team import load_team

    spec = load_team(path)
    refusal = refuse_robots(spec)
    if refusal is not None:
        return error(f"{path}: {refusal}")
    out = out or Path("runs") / spec.name
    return LiveRun(spec.name, lambda attachment: run_team(spec, attachment, out=out, seed=seed),
                   out, schemes=lambda name: None, speed=speed, paused=paused,
                   steering=TeamSteering())


def add_team(sub: argparse._SubParsersAction) -> None:
    """``shary team up``: the engine's (a team file), and a seam-welding scenario with its
    world (sim/weld/agent.py), every agent its own process."""
    from shary.commands.distributed import add_team as add_engine_team

    add_engine_team(sub, run=cmd_team_up, what="SCENARIO|TEAM.yaml",
                    about="a seam-welding scenario (built-in name or file: its world, robots "
                    "and people each run as their own process) or a team file")


def cmd_team_up(args: argparse.Namespace) -> int:
    from shary.commands.distributed import cmd_team_up as engine_team_up
    from sim.scenario import builtin_scenarios
    from sim.weld.agent import team_up_scenario

    if not args.team.exists():  # a built-in scenario's name
        path = builtin_scenarios().get(str(args.team))
        if path is None or _weld_scenario(path) is None:
            names = [n for n, p in builtin_scenarios().items()
                     if _weld_scenario(p) is not None]
            return error(f"no team file or team scenario {str(args.team)!r}"
                         f"{did_you_mean(str(args.team), names)} (team scenarios: "
                         f"{', '.join(names)})", json_mode=args.json)
        return team_up_scenario(args, path)
    path = _weld_scenario(args.team)
    return engine_team_up(args) if path is None else team_up_scenario(args, path)


def _weld_scenario(name: Path) -> Path | None:
    """The seam-welding scenario ``name`` names (a built-in name or a file), or None when it
    is a team file (or names nothing: the team file's reader says what is wrong)."""
    from sim.scenario import builtin_scenarios
    from sim.weld.scenario import is_weld_scenario

    path = builtin_scenarios().get(str(name)) if not name.exists() else name
    if path is None:
        return None
    try:
        return path if is_weld_scenario(yamlsafe.load_file(path).data) else None
    except FileError:
        return None


def add_world(sub: argparse._SubParsersAction) -> None:
    from shary.commands.distributed import DEFAULT_ENDPOINT, add_common, endpoint

    p = sub.add_parser("world", help="run a seam-welding scenario's world (the PyBullet site) "
                       "as an agent of a distributed team (Zenoh), or with --ros a living-room "
                       "scenario's world as the simulated Jido on ROS 2",
                       description="Run the scenario's world in this process: it joins the "
                       "team whose managers listen at --connect (shary team up SCENARIO), "
                       "performs the robots' atomic tasks and the people's work on site, and "
                       "shares what it perceives.  With --ros, the living room serves the "
                       "jido-sim binding's interfaces on ROS 2 for 'shary run SCENARIO --ros' "
                       "and serves that one run: it stops when the supervisor leaves "
                       "(docs/ros2.md).")
    p.add_argument("scenario", metavar="SCENARIO",
                   help="a seam-welding scenario (built-in name or file); with --ros, a "
                   "living-room scenario")
    p.add_argument("--ros", action="store_true",
                   help="serve the scenario's living room as the simulated Jido on ROS 2 "
                   "(the jido-sim binding's interfaces), for 'shary run SCENARIO --ros'")
    p.add_argument("--seconds", type=float, metavar="S",
                   help="with --ros: stop after S seconds (default: run until the "
                   "supervisor leaves, or Ctrl-C)")
    p.add_argument("--quiet", action="store_true",
                   help="with --ros: do not print what happens in the world")
    p.add_argument("--connect", type=endpoint, default=DEFAULT_ENDPOINT,
                   metavar="tcp/HOST:PORT",
                   help=f"where the team's managers listen (default {DEFAULT_ENDPOINT})")
    add_common(p)
    p.set_defaults(func=cmd_world)


def cmd_world(args: argparse.Namespace) -> int:
    from sim.scenario import find_scenario

    try:
        path = find_scenario(args.scenario)
    except KeyError as err:
        return error(err.args[0])
    if args.ros:
        from sim.rosrun import cmd_world_ros

        return cmd_world_ros(args, path)
    if _weld_scenario(path) is None:
        return error(f"{args.scenario}: not a seam-welding scenario, whose world joins a "
                     "Zenoh team as its own agent; a living-room scenario's world runs on "
                     "ROS 2 as the simulated Jido: 'shary world --ros "
                     f"{shlex.quote(args.scenario)}' (docs/ros2.md)")
    from sim.weld.agent import cmd_world as run_world

    return run_world(args, path)


def add_fuzz(sub: argparse._SubParsersAction) -> None:
    from sim.fuzz.behaviours import FAMILIES

    p = sub.add_parser("fuzz", help="a behaviour campaign: run a family's scenarios with "
                       "people who behave at random, and check that the supervisor never "
                       "stalls, lies or speaks to no one")
    p.add_argument("family", choices=FAMILIES, help="the scenarios varied: stack (the shared "
                   "plan), living-room (give and clean up), weld (the HRI/OS team), dialogue "
                   "(requests, cancels, sessions, informs)")
    p.add_argument("--runs", type=int, default=20, metavar="N", help="how many runs (default 20)")
    p.add_argument("--seed", type=int, default=1, metavar="S",
                   help="the first run's seed; run i has seed S+i (default 1)")
    p.add_argument("--replay", type=int, metavar="SEED",
                   help="run that one seed again, telling its story and the scenario drawn")
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="with --replay: write the run's files there (log.sqlite, ...)")
    p.add_argument("--jobs", type=int, default=1, metavar="J",
                   help="worker processes (default 1); the report is the same for any J")
    add_json_flag(p, "the campaign: verdicts, invariants, violations, each run")
    p.set_defaults(func=cmd_fuzz)


def cmd_fuzz(args: argparse.Namespace) -> int:
    from sim.fuzz.campaign import Campaign, campaign, run_one
    from sim.fuzz.report import print_campaign, progress_line

    if not 1 <= args.runs <= 100_000:
        return error(f"--runs {args.runs}: from 1 to 100000", json_mode=args.json)
    if not 1 <= args.jobs <= 64:
        return error(f"--jobs {args.jobs}: from 1 to 64", json_mode=args.json)
    if args.out is not None and args.replay is None:
        return error("--out goes with --replay SEED (a campaign writes no files)",
                     json_mode=args.json)
    if args.replay is not None:
        from sim.fuzz.behaviours import draw
        from sim.narration import ConsoleReport

        variation = draw(args.family, args.replay)
        if not args.json:
            _out.print(f"[bold]seed {args.replay}[/bold]: {escape(variation.base)} with "
                       f"{escape(variation.story)}")
            _out.print(escape(variation.text()), end="")
            if variation.team is not None:
                _out.print(escape(variation.team_text() or ""), end="")
        import time

        wall = time.perf_counter()
        outcome = run_one(args.family, args.replay, variation=variation, out=args.out,
                          report=None if args.json else ConsoleReport(_out))
        result = Campaign(args.family, args.replay, [outcome], time.perf_counter() - wall)
    else:
        result = campaign(args.family, args.runs, args.seed, jobs=args.jobs,
                          progress=None if args.json else progress_line(_out))
    if args.json:
        emit_json(result.as_dict())
    else:
        print_campaign(_out, result)
    return 1 if result.violations else 0

"""``shary agent`` and ``shary team up``: a team spread over processes, over Zenoh.

``shary team up TEAM.yaml`` runs the managers and the shared clock here and
starts every other agent as its own process (``shary agent NAME``), on
loopback, with a line for each member that joins or leaves and each task
that runs or ends.  ``shary agent NAME --team TEAM.yaml --connect
tcp/HOST:PORT`` runs one agent, here or on another machine.  See
docs/distributed.md.
"""

from __future__ import annotations

import argparse
import math
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from shary.log.terminal import add_json_flag, emit_json, error, escape
from shary.log.terminal import out as _out
from shary.transport.zconfig import zenoh_reason
from userfiles.limits import seconds

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"


def endpoint(text: str) -> str:
    proto, _, rest = text.partition("/")
    host, _, port = rest.rpartition(":")
    if proto not in ("tcp", "udp", "tls", "quic") or not host or not port.isdigit():
        raise argparse.ArgumentTypeError(f"{text!r} is not a Zenoh endpoint "
                                         "(write tcp/HOST:PORT, e.g. tcp/127.0.0.1:7447)")
    return text


def _duration(text: str) -> float:
    try:
        return seconds(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a duration (10min, 90s …)") from None


def _port(text: str) -> int:
    if not text.isdigit() or not 0 < int(text) < 65536:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port (1 to 65535)")
    return int(text)


def _loss(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not 0.0 <= value <= 1.0:  # NaN fails too
        raise argparse.ArgumentTypeError(f"{text!r} is not a share of messages (a number "
                                         "from 0 to 1, e.g. 0.3)")
    return value


def add_common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--log-dir", type=Path, metavar="DIR",
                   help="write one context log per agent here (NAME.sqlite)")
    p.add_argument("--seed", type=int, default=0, help="the random seed (default 0)")
    p.add_argument("--zenoh-config", type=Path, metavar="FILE.json5",
                   help="a Zenoh configuration (JSON5) merged over shary's safe defaults: "
                   "TLS certificates, mTLS, access control (docs/distributed.md)")
    p.add_argument("--no-share-log", dest="share_log", action="store_false",
                   help="do not forward the agents' log records to the managers")


def zenoh_settings(args: argparse.Namespace) -> dict[str, Any] | None:
    """The checked ``--zenoh-config`` (a FileError if refused), or None."""
    if args.zenoh_config is None:
        return None
    from shary.transport.zconfig import load_settings

    return load_settings(args.zenoh_config)


def passed_on(args: argparse.Namespace) -> list[str]:
    """The options of ``team up`` its members' processes take too."""
    return ([] if args.share_log else ["--no-share-log"]) + (
        ["--zenoh-config", str(args.zenoh_config)] if args.zenoh_config else [])


def add_agent(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("agent", help="run one agent of a team as its own process (Zenoh)",
                       description="Run one agent of a team file in this process; it joins "
                       "the team whose managers listen at --connect (shary team up).")
    p.add_argument("agent", metavar="AGENT", help="the agent's name in the team file")
    p.add_argument("--team", type=Path, required=True, metavar="TEAM.yaml",
                   help="the team file")
    p.add_argument("--connect", type=endpoint, default=DEFAULT_ENDPOINT,
                   metavar="tcp/HOST:PORT",
                   help=f"where the team's managers listen (default {DEFAULT_ENDPOINT})")
    add_common(p)
    faults = p.add_argument_group("faults (a testing aid: a bad link at this agent's port, "
                                  "both ways)")
    faults.add_argument("--inject-latency", type=_duration, default=0.0, metavar="DURATION",
                        help="delay every message from or to this agent (e.g. 2s), on the "
                        "team's clock")
    faults.add_argument("--inject-loss", type=_loss, default=0.0, metavar="SHARE",
                        help="drop this share of the messages from or to this agent (0 to 1)")
    faults.add_argument("--fault-seed", type=int, default=0, metavar="N",
                        help="the seed of the dropped messages' draw (default 0)")
    p.set_defaults(func=cmd_agent)


def add_team(sub: argparse._SubParsersAction, *,
             run: Callable[[argparse.Namespace], int] | None = None, what: str = "TEAM.yaml",
             about: str = "the team file") -> None:
    """Add ``shary team up``; the simulator adds it with scenarios too (``run``, ``what``)."""
    p = sub.add_parser("team", help=f"run a team: `shary team up {what}` (every agent its "
                       "own process)")
    verbs = p.add_subparsers(dest="verb", metavar="VERB", required=True)
    up = verbs.add_parser("up", help="start the managers here and every agent as its own "
                          "process, on loopback, and run the goal",
                          description="Run the team's managers and shared clock here, start "
                          "each agent as `shary agent`, and run the goal until it is over.")
    up.add_argument("team", type=Path, metavar=what, help=about)
    up.add_argument("--listen", type=endpoint, default=DEFAULT_ENDPOINT,
                    metavar="tcp/HOST:PORT",
                    help=f"where the managers listen (default {DEFAULT_ENDPOINT}: loopback)")
    up.add_argument("--limit", type=_duration, default=3600.0, metavar="DURATION",
                    help="stop after this much simulated time (default 1h)")
    up.add_argument("--pace", type=float, default=0.0, metavar="S",
                    help="wall seconds per simulated second (default 0: as fast as it goes)")
    up.add_argument("--remote", action="append", default=[], metavar="AGENT",
                    help="do not start AGENT here: it joins from elsewhere (repeatable)")
    up.add_argument("--wait", type=_duration, default=30.0, metavar="DURATION",
                    help="how long to wait for every agent to join, and for a lost one to "
                    "come back when the goal needs it (default 30s)")
    up.add_argument("--console", action="store_true",
                    help="serve the operator console for the run (it starts when the first "
                    "page connects; Ctrl-C stops the console once the run is over)")
    up.add_argument("--console-port", type=_port, default=8765, metavar="N",
                    help="the console's port (default 8765)")
    up.add_argument("--console-host", default="127.0.0.1", metavar="HOST",
                    help="the console's address (default 127.0.0.1: this machine only)")
    add_common(up)
    add_json_flag(up, "the outcome")
    up.set_defaults(func=run or cmd_team_up)


def cmd_agent(args: argparse.Namespace) -> int:

    from shary.team import load_team
    from shary.transport.distributed import Member
    from shary.transport.port import Faults

    settings = zenoh_settings(args)
    spec = load_team(args.team)
    if args.agent not in spec.agents:
        return error(f"{args.team}: no agent {args.agent!r} in team {spec.name!r} (its "
                     f"agents: {', '.join(spec.agents)})")
    faults = (Faults(loss=args.inject_loss, latency=args.inject_latency, seed=args.fault_seed)
              if args.inject_loss or args.inject_latency else None)
    return take_part(lambda: Member(spec, args.agent, connect=args.connect,
                                    logdir=args.log_dir, seed=args.seed, faults=faults,
                                    share_log=args.share_log, settings=settings),
                     args.connect)


def take_part(join: Callable[[], Any], connect: str) -> int:
    """Join the team at ``connect`` (``join()`` builds the process's member: an agent, the
    world) and take part until the run stops; the exit status (0 when the run ended,
    whatever its outcome; 2 when the member could not join)."""
    import zenoh

    try:
        member = join()
    except zenoh.ZError as exc:
        return error(f"cannot join the team at {connect}: {zenoh_reason(exc)} "
                     f"({check_there(connect)})")
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))  # close the session on a kill
    reason = member.run()
    return 0 if reason in ("done", "failed", "time is up", "stopped") else 1


def cmd_team_up(args: argparse.Namespace) -> int:
    from shary.team import load_team

    return team_up(args, load_team(args.team))


Prepare = Callable[[Any], Any]
"""Called with the :class:`~shary.transport.distributed.Conductor` before the goal starts."""
Finish = Callable[[Any, "str | None", Path, float], list[str]]
"""Called with the conductor, the goal's outcome, the log folder and the wall seconds once
the run is over; prints the verdict and returns its differences (none: passed)."""


class NotRun(Exception):
    """The run cannot start: the managers cannot listen, members did not join."""


def team_up(args: argparse.Namespace, spec: Any, *, world: list[str] | None = None,
            prepare: Prepare | None = None, finish: Finish | None = None,
            settle: bool = False) -> int:
    """Run ``spec``'s managers here and start its members (see the module's docstring);
    ``settle``: see :meth:`~shary.transport.distributed.Conductor.run`.

    A team with robots needs its world agent: ``world`` is the command that starts it
    (``shary world SCENARIO``, which the simulator's ``team up SCENARIO`` gives), or it
    joins from elsewhere (``--remote world``).  With ``--console`` the run starts when the
    first page connects, and the console is served until Ctrl-C
    (:mod:`shary.console.distributed`)."""
    import zenoh

    from shary.team.world import WORLD
    from shary.transport.distributed import Conductor

    settings = zenoh_settings(args)
    unknown = [n for n in args.remote if n not in spec.agents and n != WORLD]
    if unknown:
        return error(f"--remote {unknown[0]}: no such agent in team {spec.name!r}",
                     json_mode=args.json)
    if spec.of_kind("robot") and world is None and WORLD not in args.remote:
        return error(f"team {spec.name!r} has robots, whose atomic tasks a world performs: "
                     "run a scenario of the team (shary team up weld-nominal), or start its "
                     "world yourself and give --remote world (docs/distributed.md)",
                     json_mode=args.json)
    if args.console and args.json:
        return error("--console and --json do not go together (the console shows the run)")
    if args.console and not args.share_log:
        return error("--console shows the agents' log records, which --no-share-log keeps "
                     "in their processes: give one of them")
    logdir = args.log_dir or Path(tempfile.mkdtemp(prefix=f"shary-{spec.name}-"))
    show = (lambda line: None) if args.json else _out.print
    children: dict[str, subprocess.Popen[bytes]] = {}
    started = time.monotonic()

    def display(kind: str, data: dict[str, Any]) -> None:
        show(_line(kind, data, children))

    def conduct() -> Any:
        try:
            return Conductor(spec, listen=args.listen, logdir=logdir, seed=args.seed,
                             pace=0.0 if args.console else args.pace, settings=settings,
                             rejoin_wait=args.wait, display=display)
        except zenoh.ZError as exc:
            raise NotRun(f"cannot listen at {args.listen}: {zenoh_reason(exc)} (another team "
                         "there? give --listen tcp/127.0.0.1:PORT)") from None

    def run(watch: Callable[[Any], Any] | None = None) -> list[str]:
        """Start the managers and the members, run the goal, judge it: the verdict's
        differences.  All in one thread (the conductor's log is SQLite's)."""

        conductor = conduct()
        try:
            if watch is not None:
                watch(conductor)
            return conducted(conductor)
        finally:
            conductor.close()
            _wait(children)

    def conducted(conductor: Any) -> list[str]:
        from shary.console.teamlive import roster

        for name in conductor.members:
            if name in args.remote:
                continue
            command = (list(world or ()) if name == WORLD else
                       ["agent", name, "--team", str(spec.file)])
            children[name] = subprocess.Popen(
                [sys.executable, "-m", "shary", *command, "--connect", args.listen,
                 "--log-dir", str(logdir), "--seed", str(args.seed), *passed_on(args)],
                stdin=subprocess.DEVNULL)
        show(f"team {escape(spec.name)}: managers at {args.listen}, "
             f"{len(conductor.members)} agents, logs in {logdir}")
        missing = conductor.wait_for_members(args.wait)
        if missing:
            raise NotRun(f"{', '.join(missing)} did not join within {args.wait:g} s")
        if prepare is not None:
            prepare(conductor)
        else:  # the roster a console shows (a scenario's prepare records it with the rest)
            conductor.team.record("team", **roster(conductor.team, conductor.members))
        running = time.monotonic()
        outcome = conductor.run(args.limit, settle=settle)
        run_wall = time.monotonic() - running
        wall = time.monotonic() - started
        _wait(children)  # their logs are complete once they have stopped
        if finish is not None:
            return finish(conductor, outcome, logdir, wall)
        now = conductor.team.loop.now()
        if args.json:
            emit_json({"team": spec.name, "outcome": outcome, "time": now,
                       "wall_seconds": round(wall, 3), "run_seconds": round(run_wall, 3),
                       "lost": conductor.lost, "logs": str(logdir),
                       "shared_records": conductor.records.by})
        else:
            show(f"goal {outcome or 'not over'} at {now:g} s simulated "
                 f"({wall:.1f} s wall); merged log: shary log {logdir}/*.sqlite")
        return [] if outcome == "done" else [f"the goal is {outcome or 'not over'} at "
                                             f"{now:g} s"]

    if args.console:
        return _console(args, spec, run, logdir)
    try:
        return 1 if run() else 0
    except NotRun as exc:
        return error(str(exc), json_mode=args.json)


@dataclass
class _Verdict:
    differences: list[str]

    def summary(self) -> dict[str, Any]:
        return {"passed": not self.differences, "differences": self.differences}


def _console(args: argparse.Namespace, spec: Any,
             run: Callable[[Callable[[Any], Any]], list[str]], logdir: Path) -> int:
    """Serve the console; the run starts with the first page (on the run's thread, where
    the conductor lives from then on) and the console stays until Ctrl-C; the verdict's
    exit status."""
    from shary.console.distributed import DistributedRun
    from shary.console.replay import named_schemes
    from shary.console.server import serve

    builtin = named_schemes()
    schemes: dict[str, Any] = {}
    if spec.of_kind("robot"):
        from shary.team.teamfile import robot_library

        schemes = {choice.scheme.name: choice.scheme
                   for task in robot_library(spec).tasks.values() for choice in task.schemes}

    def runner(attachment: Any) -> _Verdict:
        return _Verdict(run(live.watch))

    live = DistributedRun(spec.name, runner, logdir,
                          schemes=lambda name: schemes.get(name) or builtin(name),
                          speed=1 / args.pace if args.pace > 0 else 0.0)
    try:
        status = serve(live, args.console_host, args.console_port, option="--console-port")
    except KeyboardInterrupt:  # uvicorn raises the Ctrl-C it stopped on again
        status = 0
    if status:
        return status
    return 0 if live.verdict is not None and live.verdict.get("passed") else 1


def _wait(children: dict[str, subprocess.Popen[bytes]]) -> None:
    """Wait a little for the members to stop, then kill the ones still there."""
    for child in children.values():
        try:
            child.wait(timeout=5)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()


def check_there(connect: str) -> str:
    """What to check when a process cannot join the team at ``connect``."""
    tls = (", and does the team's CA accept this process's certificate"
           if connect.startswith("tls/") else "")
    return f"is `shary team up` running there{tls}?"


def _line(kind: str, data: dict[str, Any], children: dict[str, Any]) -> str:
    agent = escape(str(data.get("agent", "")))
    task = escape(str(data.get("task", "")))
    if kind == "agent-joined":
        child = children.get(data.get("agent", ""))
        pid = f" (pid {child.pid})" if child is not None and child.poll() is None else ""
        return f"+ {agent} joined{pid}"
    if kind == "agent-left":
        return f"- {agent} left"
    if kind == "rejoined":
        holds = ", ".join(map(escape, data.get("holds") or [])) or "no task"
        return (f"+ {agent} rejoined at {data.get('at', 0):g} s: told {data.get('tasks')} "
                f"tasks ({data.get('done')} done), {data.get('questions')} open questions; "
                f"it holds {holds}")
    if kind == "waiting-for-members":
        return (f"  waiting up to {data.get('within', 0):g} s for "
                f"{', '.join(map(escape, data.get('missing', [])))} to come back")
    if kind == "clock-waiting":
        return (f"  the clock has waited {data.get('seconds', 0):g} s at "
                f"{data.get('at', 0):g} s for {escape(str(data.get('why')))}")
    if kind == "agent-lost":
        return f"! {agent} lost while {data.get('state')} {task}: offered again"
    if kind == "task-running":
        return f"  {task} running: {agent}"
    if kind == "task-done":
        return f"  {task} done by {agent}"
    if kind == "task-failed":
        return f"  {task} failed ({agent}): {escape(str(data.get('reason', '')))}"
    if kind == "question":
        image = (data.get("data") or {}).get("image")
        return f"  {agent} asks: {escape(str(data.get('text')))}" + (
            " " + escape(f"[image {image}]") if image else "")
    if kind == "answer" and data.get("expired"):
        return f"  nobody answered in time: taken as {escape(str(data.get('value')))}"
    if kind == "answer":
        return f"  {agent} answered {escape(str(data.get('value')))}"
    if kind == "message-refused":
        return f"! refused a message on {escape(str(data.get('key')))}: " \
               f"{escape(str(data.get('reason')))}"
    return f"  goal over: {escape(str(data.get('outcome')))}"

"""A seam-welding scenario spread over processes: the world agent and ``team up SCENARIO``.

``shary world SCENARIO --connect tcp/HOST:PORT`` runs :class:`WorldMember`: the
scenario's :class:`~sim.weld.world.WeldWorld` (the PyBullet site, its
executors, perception and avatars) in its own process, a member of the team's
shared clock like any agent (its physics ticks are timers on its loop, so its
simulated time is the team's), with its own context log ``world.sqlite``.

``shary team up SCENARIO`` (:func:`team_up_scenario`) runs the managers and the
clock here, with what the in-process run wires beside the team (the spatial
reasoner's service on the facts the world shares, the scenario's script), and
starts the world and every robot and person as their own processes
(``shary world``, ``shary agent``).  When the goal is over it judges the
scenario's ``expect`` on the merged logs of every process, as ``shary run``
judges its one log, and draws the timeline of the merged logs (a lane per agent).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from shary.facts.database import FactDatabase
from shary.kernel.loop import EventLoop
from shary.log.contextlog import merged_events
from shary.log.terminal import emit_json, escape
from shary.log.terminal import out as _out
from shary.log.timeline import render_timeline
from shary.team.world import WORLD, connect_world
from shary.transport.distributed import CONDUCTOR, Participant, agent_log
from shary.transport.logshare import Forwarder, SharedLog
from shary.transport.zenohport import LOOPBACK, Settings, ZenohPort, session_config
from userfiles.outputs import write_output

from .run import offer_spatial, record_members, schedule_script
from .scenario import WeldScenario, judge, load_weld_scenario
from .site import WeldSite
from .world import WeldWorld


class WorldMember(Participant):
    """The scenario's world in this process, on the team's shared clock (see the module).
    Pictures go to ``logdir`` with the log (none without a folder, as in ``shary run``)."""

    def __init__(self, scenario: WeldScenario, *, connect: str = LOOPBACK,
                 logdir: Path | None = None, seed: int = 0, share_log: bool = True,
                 settings: Settings | None = None):
        log = agent_log(logdir, WORLD, seed)
        forwarder = Forwarder(WORLD) if share_log else None  # its rows to the managers too
        writer = SharedLog(log, forwarder) if forwarder is not None else log
        loop = EventLoop(seed=seed)
        if log is not None:
            loop.idle_hooks.append(log.flush)  # the log commits before the port sends

        def record(kind: str, task: str | None = None, agent: str | None = None,
                   **data: Any) -> None:
            if writer is not None:
                writer.record(loop.now(), kind, task=task, agent=agent or WORLD,
                           **{k: v for k, v in data.items() if v is not None})

        port = ZenohPort(loop, record, team=scenario.team.name, name=WORLD, local=[WORLD],
                         config=session_config(mode="client", connect=[connect],
                                               settings=settings))
        if forwarder is not None:
            forwarder.attach(port)
        super().__init__(WORLD, loop, port, log)
        self.site = WeldSite()
        try:
            self.world = WeldWorld(scenario, self.site, port, FactDatabase(), record, logdir)
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        try:
            super().close()
        finally:
            self.site.close()


def cmd_world(args: argparse.Namespace, path: Path) -> int:
    """``shary world SCENARIO``: the scenario's world joins the team at ``--connect``."""
    from shary.commands.distributed import take_part, zenoh_settings

    settings = zenoh_settings(args)
    scenario = load_weld_scenario(path)
    return take_part(lambda: WorldMember(scenario, connect=args.connect, logdir=args.log_dir,
                                         seed=args.seed, share_log=args.share_log,
                                         settings=settings), args.connect)


def team_up_scenario(args: argparse.Namespace, path: Path) -> int:
    """``shary team up SCENARIO``: see the module's docstring."""
    from shary.commands.distributed import team_up

    scenario = load_weld_scenario(path)
    args.limit = scenario.timeout

    def prepare(conductor: Any) -> None:
        team = conductor.team
        connect_world(team)  # the managers' view: the robots' executors are the world's
        record_members(team, conductor.members)
        offer_spatial(team)
        schedule_script(team, scenario)

    def finish(conductor: Any, outcome: str | None, logdir: Path, wall: float) -> list[str]:
        team = conductor.team
        end = team.loop.now()
        team.record("run-end", scenario=scenario.name)
        conductor.log.flush()
        logs = [logdir / f"{CONDUCTOR}.sqlite",
                *sorted(p for p in logdir.glob("*.sqlite") if p.stem != CONDUCTOR)]
        with merged_events(logs) as events:
            merged = list(events)
        rows = [(e.time, e.kind, e.task, e.agent, e.data) for e in merged]
        lanes = [e for e in merged if e.agent != WORLD  # the agents' lanes, not processes'
                 and e.kind not in ("agent-joined", "agent-left")]
        write_output(logdir / "timeline.svg", render_timeline(lanes, scenario.name))
        differences = judge(scenario.expect, rows, outcome, end)
        if conductor.halted:
            differences.append(f"the run stopped early: {conductor.halted}")
        if end >= scenario.timeout - 1e-9:
            differences.append(f"the run was still going at the timeout "
                               f"({scenario.timeout:g}s)")
        passed = not differences
        if args.json:
            emit_json({"scenario": scenario.name, "passed": passed,
                       "differences": differences, "outcome": outcome, "time": end,
                       "wall_seconds": round(wall, 3), "seed": args.seed,
                       "lost": conductor.lost, "logs": str(logdir)})
        else:
            verdict = ("[bold green]PASSED[/bold green]" if passed
                       else "[bold red]FAILED[/bold red]")
            _out.print(f"{verdict} {scenario.name}: {end:.1f} s simulated in {wall:.1f} s "
                       f"wall, every agent its own process, seed {args.seed}")
            for difference in differences:
                _out.print(f"  - {escape(difference)}")
            _out.print(f"[dim]logs, pictures and timeline.svg in {escape(str(logdir))}/: "
                       f"shary log {escape(str(logdir))}/*.sqlite[/dim]")
        return differences

    return team_up(args, scenario.team,
                   world=["world", str(path)], prepare=prepare, finish=finish, settle=True)

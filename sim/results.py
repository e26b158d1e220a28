"""What a run gives back, for the living room and the site alike: its result, the
in-memory log a run without an output folder keeps, the step between two looks at
whether it is over, and what the commands say of a run's folder (what it wrote, what it
replaces)."""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from shary.log.terminal import emit_json, escape
from shary.log.terminal import out as _out

CHUNK = 0.1
"""Simulated seconds advanced between two looks at whether the run is over (so the
reported end is at most this much after the last thing that happened)."""


@dataclass
class RunResult:
    """What :func:`run_scenario` found and wrote."""

    scenario: str
    passed: bool
    differences: list[str]
    simulated_seconds: float
    wall_seconds: float
    """Wall time of the simulation itself (the world built, the files read)."""
    setup_seconds: float
    """Wall time to build the world, the people and the supervisor."""
    seed: int
    physics_steps: int | None
    """Physics steps of the world (None over ROS 2: the world steps in its own process)."""
    noise_misses: int | None = 0
    """Facts the injected perception noise made the detector miss (None over ROS 2)."""
    over: str = "one process"
    """Where the world ran: ``one process`` with the supervisor, or ``ros2`` (the
    supervisor reached it only through ROS 2, on the wall clock)."""
    outputs: dict[str, str] = field(default_factory=dict)
    events: list[tuple[float, str, str | None, str | None, dict[str, Any]]] = field(
        default_factory=list, repr=False)
    """The context log's rows ``(time, kind, task, agent, data)``, kept when the run wrote
    no output folder (otherwise they are in its ``log.sqlite``)."""
    truth: frozenset[tuple[str, str, str]] = field(default_factory=frozenset, repr=False)
    """What the world makes true at the end, whatever the robot perceived: where each
    object is (``isOn``, ``isIn``), who holds what; a site's panels ``mounted`` and seams
    ``welded``.  What a campaign checks a verdict against (:mod:`sim.fuzz`)."""

    @property
    def real_time_factor(self) -> float:
        return self.simulated_seconds / self.wall_seconds if self.wall_seconds > 0 else math.inf

    def summary(self) -> dict[str, Any]:
        out = asdict(self)
        del out["events"], out["truth"]
        out["outcome"] = "passed" if self.passed else "failed"
        out["real_time_factor"] = round(self.real_time_factor, 1)
        out["simulated_seconds"] = round(self.simulated_seconds, 2)
        out["wall_seconds"] = round(self.wall_seconds, 3)
        out["setup_seconds"] = round(self.setup_seconds, 3)
        return out


class MemoryLog:
    """The context log's interface, kept in memory when no output folder is asked for."""

    def __init__(self) -> None:
        self.events: list[tuple[float, str, str | None, str | None, dict[str, Any]]] = []

    def record(self, t: float, kind: str, *, task: str | None = None,
               agent: str | None = None, **data: Any) -> int:
        self.events.append((t, kind, task, agent, data))
        return len(self.events)

    def flush(self) -> None:
        pass

    def __enter__(self) -> MemoryLog:
        return self

    def __exit__(self, *exc: object) -> None:
        pass


def wrote(out: Path, outputs: dict[str, str]) -> str:
    """The line that says which files a run wrote in ``out`` (the snapshots counted)."""
    files = ", ".join(Path(v).name for k, v in outputs.items() if k != "snapshots")
    snapshots = (f" and {len(outputs['snapshots'].split(', '))} snapshots"
                 if "snapshots" in outputs else "")
    return f"[dim]wrote {escape(str(out))}/: {escape(files)}{snapshots}[/dim]"


def earlier_run(out: Path) -> str | None:
    """What to say when ``out`` holds an earlier run that a new one will replace (``shary
    run`` and ``shary serve`` both write to runs/SCENARIO by default, the latest run of
    each scenario in one known place); None when there is none."""
    log = out / "log.sqlite"
    if not log.is_file():
        return None
    when = time.strftime("%Y-%m-%d %H:%M", time.localtime(log.stat().st_mtime))
    return (f"{out}/ holds an earlier run (of {when}): this run replaces its files "
            f"(--out DIR keeps runs apart)")


def tell_run(result: RunResult, out: Path, replacing: str | None, *, json_mode: bool,
             quiet: bool) -> int:
    """What ``shary run`` prints at a run's end, in one process or over ROS 2: its summary
    as JSON, or the verdict, why it failed and (unless quiet) the files written; the exit
    status (1 when the scenario's expectations are not met)."""
    if json_mode:
        emit_json({**result.summary(), "out": str(out),
                   "replaced_earlier_run": replacing is not None})
        return 0 if result.passed else 1
    verdict = "[bold green]PASSED[/bold green]" if result.passed else "[bold red]FAILED[/bold red]"
    if result.over == "ros2":
        said = (f"{result.scenario} over ROS 2: {result.simulated_seconds:.1f} s on the wall "
                f"clock")
    else:
        said = (f"{result.scenario}: {result.simulated_seconds:.1f} s simulated in "
                f"{result.wall_seconds:.2f} s (x{result.real_time_factor:.0f} real time)")
    _out.print(f"{verdict} {said}, seed {result.seed}")
    for difference in result.differences:
        _out.print(f"  - {escape(difference)}")
    if not quiet:
        _out.print(wrote(out, result.outputs))
    return 0 if result.passed else 1

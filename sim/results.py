"""What a run gives back, for the living room and the site alike: its result, the
in-memory log a run without an output folder keeps, and the step between two looks at
whether it is over."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

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
    physics_steps: int
    noise_misses: int = 0
    """Facts the injected perception noise made the detector miss."""
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

"""A behaviour campaign: many runs of a family, each with a drawn behaviour, judged.

:func:`campaign` runs seeds ``seed … seed + runs - 1`` of a family: each seed
draws a behaviour (:func:`sim.fuzz.behaviours.draw`), the varied scenario runs
headless through :func:`sim.run.run_scenario` (what ``shary run`` runs, with
the same seed, no output folder), and the invariants
(:mod:`sim.fuzz.invariants`) read its log rows and the world's end state.  A
seed is a complete recipe: ``shary fuzz FAMILY --runs 1 --seed K`` runs
exactly run K again.  With ``jobs`` > 1 the runs are shared among worker
processes (each run is independent; the results come back in seed order, so
the report does not depend on the number of jobs).

A run that raises is a result too (its verdict invariant says what was
raised), so one bad run never hides the others.
"""

from __future__ import annotations

import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .behaviours import Variation, draw
from .invariants import INVARIANTS, Run, verdict
from .keys import keys_matter

__all__ = ["Campaign", "Outcome", "campaign", "command", "judge", "run_one"]


@dataclass
class Outcome:
    """One run of a campaign: what was drawn, the verdict, the invariants violated."""

    seed: int
    base: str
    behaviour: str
    verdict: str | None
    reason: str
    simulated_seconds: float
    wall_seconds: float
    violations: dict[str, str] = field(default_factory=dict)
    """Invariant name -> what was seen (only the invariants violated)."""
    checked: tuple[str, ...] = ()
    """The invariants that apply to this run's family."""
    keys: int = 0
    """How many keys were drawn for this run."""
    unreached: int = 0
    """How many of them never had their moment in it (:mod:`sim.fuzz.keys`)."""

    def as_dict(self) -> dict[str, Any]:
        return {"seed": self.seed, "base": self.base, "behaviour": self.behaviour,
                "verdict": self.verdict, "reason": self.reason or None,
                "simulated_seconds": round(self.simulated_seconds, 2),
                "wall_seconds": round(self.wall_seconds, 3), "violations": self.violations,
                "keys": self.keys, "keys_unreached": self.unreached}


@dataclass
class Campaign:
    """A campaign's runs, in seed order."""

    family: str
    seed: int
    outcomes: list[Outcome]
    wall_seconds: float

    @property
    def violations(self) -> list[tuple[Outcome, str, str]]:
        """(run, invariant, what was seen) for every violation, by seed then invariant."""
        order = [i.name for i in INVARIANTS]
        return [(o, name, o.violations[name]) for o in self.outcomes
                for name in sorted(o.violations, key=order.index)]

    def as_dict(self) -> dict[str, Any]:
        """The campaign as one JSON document (its shape: docs/cli.md, ``shary fuzz``)."""
        verdicts: dict[str, int] = {"achieved": 0, "failed": 0, "none": 0}
        for o in self.outcomes:
            verdicts[o.verdict or "none"] += 1
        return {
            "family": self.family, "seed": self.seed, "runs": len(self.outcomes),
            "wall_seconds": round(self.wall_seconds, 2),
            "simulated_seconds": round(sum(o.simulated_seconds for o in self.outcomes), 1),
            "verdicts": verdicts,
            "keys": {"drawn": sum(o.keys for o in self.outcomes),
                     "unreached": sum(o.unreached for o in self.outcomes)},
            "invariants": [{"name": i.name, "says": i.says,
                            "checked": sum(i.name in o.checked for o in self.outcomes),
                            "violated": sum(i.name in o.violations for o in self.outcomes)}
                           for i in INVARIANTS],
            "violations": [{"seed": o.seed, "invariant": name, "what": what, "base": o.base,
                            "behaviour": o.behaviour, "command": command(self.family, o.seed)}
                           for o, name, what in self.violations],
            "results": [o.as_dict() for o in self.outcomes],
        }


def command(family: str, seed: int) -> str:
    """The one line that runs seed ``seed`` of a campaign again, with its story."""
    return f"shary fuzz {family} --replay {seed}"


def run_one(family: str, seed: int, *, out: Path | None = None, report: Any = None,
            variation: Variation | None = None) -> Outcome:
    """Draw run ``seed``'s behaviour, run it, judge it (see the module's docstring);
    ``out`` writes the run's files there (as ``shary run --out``), ``report`` is told
    its story."""
    from shary.log.contextlog import read_events

    variation = variation or draw(family, seed)
    checked = tuple(i.name for i in INVARIANTS if family in i.families)
    wall = time.perf_counter()
    try:
        scenario = variation.load()
        result = variation.run(seed, out=out, report=report)
    except Exception as err:  # a crash is a finding, reported like the others
        where = traceback.extract_tb(err.__traceback__)[-1]
        what = (f"raised {type(err).__name__}: {err} "
                f"({Path(where.filename).name}:{where.lineno})")
        return Outcome(seed, variation.base, variation.story, None, "", 0.0,
                       time.perf_counter() - wall, {"verdict": what}, checked)
    rows = result.events if out is None else [
        (e.time, e.kind, e.task, e.agent, e.data) for e in read_events(out / "log.sqlite")]
    state, reason, violations = judge(family, scenario, result, rows)
    # every key drawn must change the run: compared row by row with runs in memory (a
    # run written to a folder is made again in memory for that)
    same = result if out is None else variation.run(seed)
    seen, unreached = keys_matter(variation, same.events, same.truth)
    if seen is not None:
        violations["keys-matter"] = seen
    return Outcome(seed, variation.base, variation.story, state, reason,
                   result.simulated_seconds, time.perf_counter() - wall, violations, checked,
                   len(variation.keys), unreached)


def judge(family: str, scenario: Any, result: Any, rows: list[Any] | None = None
          ) -> tuple[str | None, str, dict[str, str]]:
    """A finished run's verdict, its stated reason, and the invariants it violated
    (name -> what was seen); ``rows`` default to the result's own log rows."""
    if hasattr(scenario, "team"):
        robot, people = "", tuple(n for n, a in scenario.team.agents.items()
                                  if a.kind == "human")
    else:
        robot, people = scenario.robot, tuple(p.name for p in scenario.people)
    run = Run(family, result.events if rows is None else rows, result.truth,
              result.simulated_seconds, scenario.timeout, robot, people, scenario)
    state, reason = verdict(run)
    violations = {}
    for invariant in INVARIANTS:
        if family in invariant.families and invariant.check is not None:
            seen = invariant.check(run)
            if seen is not None:
                violations[invariant.name] = seen
    return state, reason, violations


def _one(job: tuple[str, int]) -> Outcome:
    return run_one(*job)


def campaign(family: str, runs: int, seed: int, *, jobs: int = 1,
             progress: Any = None) -> Campaign:
    """Run seeds ``seed`` … ``seed + runs - 1`` of ``family`` (see the module's
    docstring); ``progress(outcome)`` is told of each run as it ends, in seed order."""
    wall = time.perf_counter()
    work = [(family, s) for s in range(seed, seed + runs)]
    outcomes = []
    if jobs > 1:
        import multiprocessing

        with multiprocessing.get_context("spawn").Pool(jobs) as pool:
            for outcome in pool.imap(_one, work):
                outcomes.append(outcome)
                if progress is not None:
                    progress(outcome)
    else:
        for job in work:
            outcomes.append(_one(job))
            if progress is not None:
                progress(outcomes[-1])
    return Campaign(family, seed, outcomes, time.perf_counter() - wall)

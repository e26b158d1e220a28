"""A team of 10 robots and 20 humans, 500 constrained tasks, 200 questions, headless.

The HRI/OS team of shary/team on the simulated clock, with everything logged
in a context log on disk.  The goal is 125 seams, each Fig. 2's four tasks:
two panels mounted (by people, in parallel), the seam welded after both, then
inspected (the rover asks a person "is this seam okay?"; a no respawns the
weld).  Besides the 125 inspection questions, robots ask 75 more (a choice
question, not waiting), spread over the run: 200 questions.  Two of the people
refuse every assignment, three ignore questions, one remote operator answers "no" to
every seam (inspections are tried five times).

The robots' executors complete each atomic task after a fixed duration on the
simulated clock: that is the benchmark's harness, not the product (the
PyBullet world fills the same port in the weld scenarios).

Measured: the run's real-time factor (simulated seconds per wall second), the
delegations (task assignments) per wall second, and the latency of each of
the Resource Manager's choices (tasks, questions, help: ranking every
candidate on every criterion, logging the explanation) at p50/p99, in wall
time and in the thread's CPU time (on a shared machine, the wall-time tail
also counts the neighbours' work).  The peer,
in the same run: the same team with capability match-making only (weights
``{capability: 1}``, the classic facilitator's delegation), to show what
ranking by six criteria costs.

    python benchmarks/team.py [--json] [--seams 125] [--runs 3]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from shary.kernel.executors import Reporter, Request
from shary.log.contextlog import ContextLog
from shary.team import Team, load_team
from shary.team.resources import ResourceManager

ROBOTS, HUMANS, REMOTE = 10, 20, 4
DURATIONS = {"drive": 20.0, "weld": 120.0, "scan": 30.0, "aim-light": 5.0}

RECIPES = """
atomic:
  drive: {params: [to]}
  weld: {params: [seam]}
  scan: {params: [seam]}
  aim-light: {params: [target]}
tasks:
  weld-seam: {params: [seam], scheme: perform}
  inspect-seam: {params: [seam], scheme: perform}
  point-light: {params: [target], scheme: perform}
recipes:
  - task: weld-seam
    act: REALIZE-TASK
    steps:
      - {do: drive, with: {to: $seam}}
      - {do: weld, with: {seam: $seam}}
  - task: inspect-seam
    act: REALIZE-TASK
    steps:
      - {do: drive, with: {to: $seam}}
      - {do: scan, with: {seam: $seam}}
      - {do: ask, with: {topic: seam-okay}}
  - task: point-light
    act: REALIZE-TASK
    steps:
      - {do: aim-light, with: {target: $target}}
"""


def team_file(folder: Path, seams: int) -> Path:
    """The benchmark's team file (and its recipes) in ``folder``."""
    (folder / "recipes.yaml").write_text(RECIPES, "utf-8")
    lines = ["team: benchmark", "recipes: [recipes.yaml]", "agents:"]
    for i in range(ROBOTS):
        skills = "[weld-seam, point-light]" if i % 2 else "[inspect-seam, point-light]"
        lines.append(f"  R{i}: {{kind: robot, skills: {skills}, at: [{i * 3}, 0]}}")
    for i in range(HUMANS):
        if i < REMOTE:
            answers = ', answers: {seam-okay: "no"}' if i == REMOTE - 1 else ""
            lines.append(f"  IVA{i}: {{kind: human, remote: true, behaviour: {{questions: "
                         f"{{reply: answer, after: [5s, 30s]}}{answers}}}}}")
            continue
        assignments = "refuse" if i in (REMOTE, REMOTE + 1) else "accept"
        questions = "ignore" if i < REMOTE + 5 else "answer"
        lines.append(f"  EVA{i}: {{kind: human, skills: [mount-panel], at: [{i * 2}, 5], "
                     f"behaviour: {{assignments: {{reply: {assignments}, after: [1s, 5s]}}, "
                     f"works: [60s, 180s], questions: {{reply: {questions}, after: [5s, 20s]}}}}}}")
    lines += ["questions:",
              "  seam-okay: {text: Is this seam okay?, priority: 5, expires: 2min,"
              ' accept: ["yes"], fallback: "yes"}',
              "  which-panel: {text: Which panel next?, type: choice, choices: [left, right],"
              " expires: 1min}",
              "goal:", "  tasks:"]
    for s in range(seams):
        x = (s % 40) * 2
        lines += [f"    mount-{s}a: {{do: mount-panel, with: {{panel: P{s}a}}, at: [{x}, 4]}}",
                  f"    mount-{s}b: {{do: mount-panel, with: {{panel: P{s}b}}, at: [{x + 1}, 4]}}",
                  f"    weld-{s}: {{do: weld-seam, with: {{seam: S{s}}}, "
                  f"after: [mount-{s}a, mount-{s}b], at: [{x}, 4]}}",
                  f"    inspect-{s}: {{do: inspect-seam, with: {{seam: S{s}}}, "
                  f"after: [weld-{s}], attempts: 5, respawn: weld-{s}, at: [{x}, 4]}}"]
    path = folder / "team.yaml"
    path.write_text("\n".join(lines) + "\n", "utf-8")
    return path


class TimedExecutor:
    """The harness: every atomic task is done after its duration on the simulated clock."""

    def __init__(self, team: Team):
        self.team = team
        self.running: dict[str, Any] = {}

    def start(self, request: Request, reporter: Reporter) -> None:
        timer = self.team.loop.call_later(DURATIONS[request.atomic], self._done, request,
                                          reporter)
        self.running[request.id] = (timer, reporter)

    def _done(self, request: Request, reporter: Reporter) -> None:
        if self.running.pop(request.id, None) is not None:
            reporter.done(request)

    def cancel(self, request: Request) -> None:
        found = self.running.pop(request.id, None)
        if found is not None:
            found[0].cancel()
            found[1].cancelled(request)


def run(path: Path, folder: Path, extra_questions: int, *, capability_only: bool,
        seed: int) -> dict[str, Any]:
    spec = load_team(path)
    if capability_only:
        spec = replace(spec, weights={"capability": 1.0})
    log_path = folder / f"run-{'peer' if capability_only else 'team'}-{seed}.sqlite"
    log = ContextLog(log_path, overwrite=True)
    team = Team(spec, log=log)
    team.loop.random.seed(seed)
    executor = TimedExecutor(team)
    for name, agent in spec.agents.items():
        if agent.kind == "robot":
            for atomic in DURATIONS:
                team.robot(name).world.register(atomic, executor)
    latencies: list[float] = []
    cpu: list[float] = []
    choose = ResourceManager.choose

    def timed(*args: Any, **kwargs: Any) -> Any:
        start, start_cpu = time.perf_counter(), time.thread_time()
        found = choose(team.resources, *args, **kwargs)
        latencies.append(time.perf_counter() - start)
        cpu.append(time.thread_time() - start_cpu)
        return found

    team.resources.choose = timed  # type: ignore[method-assign]
    robots = [team.robot(a.name) for a in spec.of_kind("robot")]
    which = spec.questions["which-panel"]
    for i in range(extra_questions):  # spread over the first simulated hour
        asker = robots[i % len(robots)]
        team.loop.call_later(30.0 + i * 3600.0 / max(1, extra_questions),
                             lambda asker=asker: team.interaction.ask(asker.name, which,
                                                                      task=asker.current))
    start = time.perf_counter()
    outcome = team.run(24 * 3600.0, step=60.0)
    wall = time.perf_counter() - start
    log.close()
    simulated = team.loop.now()
    questions = team.interaction.answered + team.interaction.expired + len(team.interaction.open)
    ms = sorted(x * 1000 for x in latencies)
    cpu_ms = sorted(x * 1000 for x in cpu)
    return {"outcome": outcome, "wall_s": wall, "simulated_s": simulated,
            "real_time_factor": simulated / wall, "delegations": team.tasks.delegations,
            "delegations_per_s": team.tasks.delegations / wall, "choices": len(ms),
            "p50_delegation_ms": statistics.median(ms),
            "p99_delegation_ms": ms[min(len(ms) - 1, int(0.99 * len(ms)))],
            "p99_delegation_cpu_ms": cpu_ms[min(len(ms) - 1, int(0.99 * len(ms)))],
            "questions": questions, "answered": team.interaction.answered,
            "expired": team.interaction.expired,
            "respawns": sum(t.respawns for t in team.tasks.tasks.values()),
            "messages": team.port.sent, "log_bytes": log_path.stat().st_size}


def _median(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Each figure's median over the runs (the outcome: the first run's)."""
    return {key: statistics.median(r[key] for r in runs) if key != "outcome" else value
            for key, value in runs[0].items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seams", type=int, default=125, help="4 tasks each (default 125)")
    parser.add_argument("--runs", type=int, default=3, help="runs of each, interleaved")
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args()
    extra = max(0, 200 - args.seams)
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        path = team_file(folder, args.seams)
        results: dict[str, list[dict[str, Any]]] = {"team": [], "peer": []}
        for seed in range(args.runs):
            results["team"].append(run(path, folder, extra, capability_only=False, seed=seed))
            results["peer"].append(run(path, folder, extra, capability_only=True, seed=seed))
    team, peer = (_median(results[name]) for name in ("team", "peer"))
    tasks = 4 * args.seams
    print(f"team: {ROBOTS} robots, {HUMANS} humans, {tasks} tasks, {team['questions']} "
          f"questions ({team['answered']} answered, {team['expired']} expired), "
          f"{team['respawns']} respawned welds; goal {team['outcome']}")
    for name, r in (("six criteria", team), ("capability only (peer)", peer)):
        print(f"  {name:<24} {r['simulated_s']:8.0f} s simulated in {r['wall_s']:6.2f} s wall: "
              f"x{r['real_time_factor']:.0f} real time; {r['delegations']} delegations, "
              f"{r['delegations_per_s']:.0f}/s; choice p50 {r['p50_delegation_ms']:.3f} ms, "
              f"p99 {r['p99_delegation_ms']:.3f} ms (CPU {r['p99_delegation_cpu_ms']:.3f} ms; "
              f"{r['choices']} choices); "
              f"{r['messages']} messages, log {r['log_bytes'] / 1e6:.1f} MB")
    print(f"  ratio to the peer: wall x{team['wall_s'] / peer['wall_s']:.2f}, "
          f"p99 choice x{team['p99_delegation_ms'] / peer['p99_delegation_ms']:.2f} "
          f"(medians of {args.runs} runs each, interleaved)")
    if args.json:
        print(json.dumps({
            "agents": ROBOTS + HUMANS, "robots": ROBOTS, "humans": HUMANS, "tasks": tasks,
            "questions": team["questions"], "outcome": team["outcome"],
            "real_time_factor": round(team["real_time_factor"], 1),
            "delegations_per_s": round(team["delegations_per_s"], 1),
            "p50_delegation_ms": round(team["p50_delegation_ms"], 4),
            "p99_delegation_ms": round(team["p99_delegation_ms"], 4),
            "p99_delegation_cpu_ms": round(team["p99_delegation_cpu_ms"], 4),
            "simulated_s": round(team["simulated_s"], 1), "wall_s": round(team["wall_s"], 3),
            "respawns": team["respawns"], "messages": team["messages"],
            "peer": {"name": "capability only", "wall_s": round(peer["wall_s"], 3),
                     "real_time_factor": round(peer["real_time_factor"], 1),
                     "p99_delegation_ms": round(peer["p99_delegation_ms"], 4)},
            "ratio_to_peer": {"wall": round(team["wall_s"] / peer["wall_s"], 3),
                              "p99_delegation": round(team["p99_delegation_ms"]
                                                      / peer["p99_delegation_ms"], 3)},
            "runs": args.runs}))


if __name__ == "__main__":
    main()

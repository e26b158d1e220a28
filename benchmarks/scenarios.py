"""Real-time factor of every built-in scenario, headless, against stepping physics.

Each scenario runs ``--repeat`` times (median wall time of the simulation
proper; the world is built and the files read before the clock starts, and
that setup is reported apart).  The peer, in the same run: stepping PyBullet
at 240 Hz with the robot and the people in the same room for as many
simulated seconds as the scenario lasted — what a naive simulation would pay
before doing any supervision at all.

    python benchmarks/scenarios.py [--json] [--repeat N] [--only NAME|FILE ...]

A scenario that fails (judged as ``shary run`` judges it) stops the benchmark with
exit status 1 and its differences: the time of a run that did not do its job means
nothing.

The JSON line: ``{"scenarios": [{"name", "passed", "simulated_seconds",
"wall_seconds", "setup_seconds", "real_time_factor",
"physics_240hz_real_time_factor", "ratio"}], "min_real_time_factor": ...}``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time

import _first  # noqa: F401  (this folder after the packages: see _first.py)

from sim.run import run_scenario
from sim.scenario import builtin_scenarios, find_scenario
from sim.world import LivingRoom

PEER_SECONDS = 5.0
"""At most this many simulated seconds of the peer are stepped: its real-time factor is a
rate, the same over 5 s as over a scenario's 150 (stepping them all took about as long
as the scenarios themselves, and the default run must end within two minutes)."""


def physics_rtf(seconds: float) -> float:
    """Simulated over wall seconds when stepping physics at 240 Hz for ``seconds`` (at most
    :data:`PEER_SECONDS`)."""
    seconds = min(seconds, PEER_SECONDS)
    with LivingRoom() as world:
        world.add_robot("pr2", "pr2like", "sofa-area")  # a second robot stands in for a person
        start = time.perf_counter()
        world.step(seconds)
        return seconds / (time.perf_counter() - start)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", action="store_true", help="print one JSON line")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--only", nargs="*", metavar="NAME|FILE",
                        help="built-in scenario names or scenario files")
    args = parser.parse_args(argv)
    try:
        chosen = ({name: find_scenario(name) for name in args.only} if args.only
                  else builtin_scenarios())
    except KeyError as err:
        print(f"benchmarks/scenarios.py: error: {err.args[0]}", file=sys.stderr)
        return 2
    rows = []
    for name, path in chosen.items():
        results = []
        for _ in range(args.repeat):
            result = run_scenario(path)
            if not result.passed:
                print(f"benchmarks/scenarios.py: error: scenario {name} failed (seed "
                      f"{result.seed}), so its time is not measured:\n  - "
                      + "\n  - ".join(result.differences), file=sys.stderr)
                return 1
            results.append(result)
        wall = statistics.median(r.wall_seconds for r in results)
        simulated = results[0].simulated_seconds
        peer = physics_rtf(simulated)
        rtf = simulated / wall
        rows.append({"name": name, "passed": True,
                     "simulated_seconds": round(simulated, 2), "wall_seconds": round(wall, 4),
                     "setup_seconds": round(statistics.median(r.setup_seconds for r in results), 4),
                     "real_time_factor": round(rtf, 1),
                     "physics_240hz_real_time_factor": round(peer, 1),
                     "ratio": round(rtf / peer, 2)})
    summary = {"scenarios": rows,
               "min_real_time_factor": min(r["real_time_factor"] for r in rows),
               "all_passed": True}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"{'scenario':<26} {'passed':>6} {'sim s':>7} {'wall s':>8} {'setup s':>8} "
              f"{'x real':>8} {'240 Hz':>8} {'ratio':>6}")
        for r in rows:
            print(f"{r['name']:<26} {str(r['passed']):>6} {r['simulated_seconds']:>7.1f} "
                  f"{r['wall_seconds']:>8.3f} {r['setup_seconds']:>8.3f} "
                  f"{r['real_time_factor']:>8.1f} {r['physics_240hz_real_time_factor']:>8.1f} "
                  f"{r['ratio']:>6.2f}")
        print(f"lowest real-time factor: {summary['min_real_time_factor']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

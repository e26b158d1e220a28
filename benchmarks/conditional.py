"""Conditional plans: HATP/EHDA's stack problems, explored and their policy chosen.

For each problem (``planner/problems/stack.yaml``, JAHRVIS's StackBuildingTask
after HATP/EHDA's public domain; ``planner/problems/stack-icra.yaml``, the
ICRA-style stack with reachability and asking for help), CPU time, median of
N runs, of:

* the exploration (:func:`planner.conditional.exploration.explore`: the AND/OR graph, a
  turn reached again explored once) -- and, as the peer in the same run, the
  same exploration as a tree (``merge=False``: every turn re-explored, as
  HATP/EHDA does);
* the policy selection (:func:`planner.conditional.policy.select`).

The leaves (root-to-leaf paths of the graph, HATP/EHDA's count of branches)
and the best policy's expected cost are printed beside HATP/EHDA's published
figures; the ratio to HATP/EHDA's own times (as reported, measured on
these machines: 1.5-2.4 s and 150-170 s) is given for the record, HATP/EHDA
itself not being installable here (a ROS package).

    python benchmarks/conditional.py [--json] [--runs N]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

# Run as a script, this folder comes first on the path, and its planner.py would shadow
# the planner package.
HERE = Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != HERE]

from planner import load_domain, load_problem  # noqa: E402
from planner.conditional.exploration import explore  # noqa: E402
from planner.conditional.policy import select  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS = {
    "stack": ("stack", "stack.yaml", 8, 18.17, 1.5),
    "icra": ("stack-icra", "stack-icra.yaml", 13, 20.0, 150.0),
}
"""name: (domain, problem file, HATP/EHDA's leaves, its best cost, its fastest time in s)."""


def cpu_ms(run) -> tuple[float, object]:  # type: ignore[no-untyped-def]
    start = time.process_time()
    value = run()
    return (time.process_time() - start) * 1000, value


def measure(domain: str, problem_file: str, runs: int) -> dict:
    problem = load_problem(ROOT / "planner" / "problems" / problem_file, load_domain(domain))
    explored, chosen, tree = [], [], []
    for _ in range(runs):
        ms, exploration = cpu_ms(lambda: explore(problem))
        explored.append(ms)
        ms, policy = cpu_ms(lambda: select(problem, exploration))  # noqa: B023
        chosen.append(ms)
        ms, _ = cpu_ms(lambda: explore(problem, merge=False))
        tree.append(ms)
    return {"explore_ms": statistics.median(explored), "select_ms": statistics.median(chosen),
            "tree_ms": statistics.median(tree), "leaves": policy.leaves,
            "best_cost": policy.cost, "turns": exploration.nodes}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args()
    figures: dict[str, float | int | None] = {"runs": args.runs}
    for name, (domain, problem_file, leaves, cost, hatpehda_s) in PROBLEMS.items():
        got = measure(domain, problem_file, args.runs)
        total = got["explore_ms"] + got["select_ms"]
        best = got["best_cost"]
        print(f"{name:<6} explore {got['explore_ms']:8.1f} ms CPU (as a tree, the peer: "
              f"{got['tree_ms']:8.1f} ms, x{got['tree_ms'] / got['explore_ms']:.1f}), "
              f"select {got['select_ms']:6.1f} ms; {got['turns']} turns")
        print(f"{'':<6} {got['leaves']} leaves (HATP/EHDA {leaves}), best policy "
              f"{'none' if best is None else f'{best:.2f}'} (HATP/EHDA {cost}); "
              f"x{hatpehda_s * 1000 / total:.0f} faster than HATP/EHDA's {hatpehda_s:g} s")
        prefix = "stack" if name == "stack" else "icra_stack"
        cost_key = "stack_best_cost" if name == "stack" else "icra_best_cost"
        figures.update({
            f"{prefix}_ms": round(total, 2),
            f"{prefix}_explore_ms": round(got["explore_ms"], 2),
            f"{prefix}_select_ms": round(got["select_ms"], 2),
            f"{prefix}_tree_ms": round(got["tree_ms"], 2),
            f"{prefix}_leaves": got["leaves"],
            cost_key: None if best is None else round(best, 4),
            f"{prefix}_speedup_vs_hatpehda": round(hatpehda_s * 1000 / total, 1)})
    if args.json:
        print(json.dumps(figures))


if __name__ == "__main__":
    main()

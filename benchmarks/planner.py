"""The HATP-like planner on the living-room clean-up, against GTPyhop, in the same run.

Problems (``benchmarks/livingroom.py``): Jido and up to two humans, 1 to 8
bottles spread over the coffee table, the sofa and the side table (every other
one out of Jido's reach when a human is there to help), one ``CleanUp`` task
per bottle, every social rule of the living-room domain selected (seven rules,
covering the six kinds: state, sequence, decomposition, effort, timeout,
crossed links).  For each size:

- **first plan**: ``plan(problem, first=True)`` (the evaluated plan: streams,
  links, score);
- **proven best**: the anytime branch and bound run until the search is
  exhausted (``result.complete``): no better plan exists; a search cut by
  ``--limit`` is reported as not proven.  The same search without the
  lookahead bound on the remaining tasks (``lookahead=False``, floor only) is
  run for comparison up to ``--lookahead-upto`` bottles;
- **GTPyhop**: the same domain in its style (``benchmarks/livingroom_gtpyhop.py``),
  its depth-first search with backtracking, first plan only (it has no costs,
  rules or criteria to find a better one with).

Every plan of ours goes through the validator (not timed).  Times are CPU
times (``time.process_time``: the machines here are shared), medians of
``--runs`` runs for the first plans, one run for the proven best.  Action
applications per second: ``actions_per_s`` is the raw rate of the search's own
step (precondition, copy-on-write state, effects, the rules' floor), replaying
the six-bottle two-agent best plan (``actions_per_s_without_rules``: the same
with no rule selected, so without the floor's links and times);
``search_actions_per_s`` the actions the
proven-best searches applied per second of search (all their other work
included).

    python benchmarks/planner.py [--json] [--runs 5] [--limit 30] [--bottles 8] [--agents 3]
"""

from __future__ import annotations

import argparse
import gc
import json
import statistics
import sys
import time
from collections.abc import Callable
from typing import Any

import _first  # noqa: F401  (this folder after the packages: see _first.py)
from livingroom import clean_up  # noqa: E402

from planner import (
    plan,  # noqa: E402
    validate,
)
from planner.model.state import State  # noqa: E402
from planner.search.branchbound import Search  # noqa: E402

HEADLINE = (6, 2)
"""The size of ``first_plan_ms`` (a 26-action plan) and ``proven_best_ms``: six bottles,
two agents, every rule."""
GOALS = {"first_plan_ms": 50.0, "proven_best_ms": 1000.0, "actions_per_s": 200_000.0}


def cpu(call: Callable[[], Any]) -> tuple[Any, float]:
    """The result of ``call`` and its CPU milliseconds."""
    gc.collect()
    start = time.process_time()
    result = call()
    return result, (time.process_time() - start) * 1000


def median_ms(call: Callable[[], Any], runs: int) -> tuple[Any, float]:
    times, result = [], None
    for _ in range(runs):
        result, spent = cpu(call)
        times.append(spent)
    return result, statistics.median(times)


def apply_rate(problem: Any, best: Any, seconds: float = 1.0) -> float:
    """Action applications per CPU second of the search's own step
    (``Search._apply``: precondition, copy-on-write state, effects, the rules' floor),
    replaying ``best``'s actions from the initial state again and again."""
    search = Search(problem)
    actions = problem.domain.actions
    steps = [(actions[a.name], tuple(a.args)) for a in best.actions]
    root = search._node(None, "replay", 0)
    applied = 0
    start = time.process_time()
    while time.process_time() - start < seconds:
        node: Any = (State(dict(problem.initial)), None, None, 0.0, 0)
        for action, args in steps:
            node = search._apply(action, args, root, node[0], None, node[2], node[3],
                                 node[4])
            assert node is not None, "the best plan no longer applies"
        applied += len(steps)
    return applied / (time.process_time() - start)


def ours_first(problem: Any, runs: int) -> dict[str, Any]:
    result, ms = median_ms(lambda: plan(problem, 60_000, first=True), runs)
    best = result.plan
    return {"first_ms": ms, "first_length": len(best.actions) if best else None,
            "first_agents": len(best.streams) if best else 0,
            "first_valid": best is not None and validate(problem, best) == [],
            "first_actions": [(a.name, *a.args) for a in best.actions] if best else None}


def ours_best(problem: Any, limit_s: float, lookahead: bool = True) -> dict[str, Any]:
    search = Search(problem, lookahead=lookahead, max_nodes=10**12)
    result, ms = cpu(lambda: search.run(limit_s * 1000))
    best = result.plan
    return {"best_ms": ms, "proven": result.complete, "score": best.score if best else None,
            "best_length": len(best.actions) if best else None,
            "best_valid": best is not None and validate(problem, best) == [],
            "expansions": result.expansions, "plans": result.plans_found,
            "applied": result.applied, "plan": best}


def theirs_first(problem: Any, runs: int) -> dict[str, Any]:
    import livingroom_gtpyhop as g

    domain, state, todo = g.domain_for(problem), g.state_of(problem), g.tasks_of(problem)
    times, found = [], None
    for _ in range(runs):
        fresh = state.copy()  # not timed
        found, spent = cpu(lambda fresh=fresh: g.find_plan(domain, fresh, todo))
        times.append(spent)
    return {"gtpyhop_ms": statistics.median(times),
            "gtpyhop_length": len(found) if found else None, "gtpyhop_plan": found}


NAMES = {"Move": "move", "Pick": "pick", "PutDown": "put_down", "Dump": "dump", "Give": "give"}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true",
                        help="end with one JSON line of figures (the table goes to stderr)")
    parser.add_argument("--runs", type=int, default=5, help="runs per first plan (median)")
    parser.add_argument("--limit", type=float, default=30.0, metavar="S",
                        help="CPU seconds a proven-best search may take")
    parser.add_argument("--bottles", type=int, default=8, help="up to this many bottles")
    parser.add_argument("--agents", type=int, default=3, help="up to this many agents")
    parser.add_argument("--lookahead-upto", type=int, default=6, metavar="N",
                        help="compare with the search without lookahead up to N bottles")
    args = parser.parse_args()
    table = sys.stderr if args.json else sys.stdout
    print(f"{'agents':>6} {'bottles':>7} | {'first ms':>8} {'len':>4} {'GTPyhop ms':>10} "
          f"{'ratio':>6} | {'best ms':>9} {'proven':>6} {'score':>6} {'len':>4} "
          f"{'expanded':>9} {'no-lookahead ms':>15}", file=table)
    rows = []
    headline = _headline(args)
    for agents in range(1, args.agents + 1):
        for bottles in range(1, args.bottles + 1):
            problem = clean_up(bottles, agents)
            row: dict[str, Any] = {"agents": agents, "bottles": bottles}
            row.update(ours_first(problem, args.runs))
            row.update(theirs_first(problem, args.runs))
            ours = [(NAMES[a[0]], *a[1:]) for a in row.pop("first_actions") or []]
            row["same_first_plan"] = ours == list(row.pop("gtpyhop_plan") or [])
            row["ratio"] = row["gtpyhop_ms"] / row["first_ms"] if row["first_ms"] else None
            row.update(ours_best(problem, args.limit))
            row["no_lookahead_ms"] = None
            if bottles <= args.lookahead_upto:
                plain = ours_best(problem, args.limit, lookahead=False)
                row["no_lookahead_ms"] = plain["best_ms"]
                if plain["proven"] and row["proven"]:
                    assert plain["score"] == row["score"], "the lookahead changed the best"
            best = row.pop("plan")
            if (bottles, agents) == headline and best is not None:
                row["apply_per_s"] = apply_rate(problem, best)
                row["apply_per_s_no_rules"] = apply_rate(
                    clean_up(bottles, agents, rules=False), best)
            rows.append(row)
            print(f"{agents:>6} {bottles:>7} | {row['first_ms']:>8.2f} "
                  f"{row['first_length'] or '-':>4} {row['gtpyhop_ms']:>10.2f} "
                  f"{row['ratio']:>6.2f} | {row['best_ms']:>9.1f} "
                  f"{'yes' if row['proven'] else 'NO':>6} {row['score'] or 0:>6g} "
                  f"{row['best_length'] or '-':>4} {row['expansions']:>9} "
                  f"{_ms(row['no_lookahead_ms']):>15}", file=table, flush=True)
    invalid = [r for r in rows if not (r["first_valid"] and r["best_valid"])]
    if invalid:
        print(f"INVALID plans: {invalid}", file=sys.stderr)
        return 1
    figures = _figures(rows, args, headline)
    for name, goal in GOALS.items():
        value = figures.get(name)
        if value is not None:
            ok = value <= goal if name.endswith("_ms") else value >= goal
            print(f"{name}: {value:,.2f} (goal {'≤' if name.endswith('_ms') else '≥'} "
                  f"{goal:,.0f}: {'met' if ok else 'NOT met'})", file=table)
    if args.json:
        print(json.dumps(figures))
    return 0


def _ms(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f}"


def _headline(args: argparse.Namespace) -> tuple[int, int]:
    """(bottles, agents) of the headline figures: six bottles and two agents, or the
    largest two-agent size asked for (``--bottles 2`` for a quick run)."""
    bottles, agents = HEADLINE
    return min(bottles, args.bottles), min(agents, args.agents)


def _figures(rows: list[dict[str, Any]], args: argparse.Namespace,
             headline: tuple[int, int]) -> dict[str, Any]:
    first = best = next(r for r in rows if (r["bottles"], r["agents"]) == headline)
    applied = sum(r["applied"] for r in rows)
    searching = sum(r["best_ms"] for r in rows) / 1000
    ratios = [r["ratio"] for r in rows if r["ratio"]]
    figures: dict[str, Any] = {
        "first_plan_ms": round(first["first_ms"], 3),
        "first_plan_actions": first["first_length"],
        "size": list(headline),
        "gtpyhop_first_plan_ms": round(first["gtpyhop_ms"], 3),
        "first_plan_ratio_vs_gtpyhop": round(first["ratio"], 2),
        "median_first_ratio_vs_gtpyhop": round(statistics.median(ratios), 2),
        "same_first_plans": sum(r["same_first_plan"] for r in rows),
        "proven_best_ms": round(best["best_ms"], 1) if best["proven"] else None,
        "proven_best_score": best["score"],
        "proven_best_actions": best["best_length"],
        "proven_best_no_lookahead_ms": (round(best["no_lookahead_ms"], 1)
                                        if best["no_lookahead_ms"] else None),
        "actions_per_s": round(best["apply_per_s"]) if "apply_per_s" in best else None,
        "actions_per_s_without_rules": (round(best["apply_per_s_no_rules"])
                                        if "apply_per_s" in best else None),
        "search_actions_per_s": round(applied / searching) if searching else None,
        "sizes": len(rows),
        "proven": sum(r["proven"] for r in rows),
        "not_proven": [[r["bottles"], r["agents"]] for r in rows if not r["proven"]],
        "runs": args.runs, "limit_s": args.limit,
    }
    return figures


if __name__ == "__main__":
    raise SystemExit(main())

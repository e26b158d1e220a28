"""Our planner against GTPyhop on the IPC 2020 HTN benchmarks, in the same run.

Ours plans the HDDL instances of the suite (``../shared/suites/ipc2020``):
Blocksworld-GTOHP p01-p30 and Childsnack p01-p30, translated once (not
timed), then searched to the first plan (``plan(problem, first=True)``: for
HDDL the depth-first search of :mod:`planner.search.depthfirst`, which returns an
evaluated plan: tree, streams, causal links); each plan is checked by our
validator (not timed) and counts only if valid.

GTPyhop plans its own hand translations of the same instances, which come
from PyPI with it (the ``bench`` extra: ``pip install -e '.[bench]'``):
``gtpyhop/examples/ipc-2020-total-order/{Blocksworld-GTOHP,Childsnack}``,
inside the ``gtpyhop`` wheel from 1.4, in the ``gtpyhop-examples`` wheel (a
dependency of ``gtpyhop``) from 2.0 (Blocksworld p01-p20, Childsnack
p01-p30).  They are run as that package's own ``benchmarking.py`` runs
them -- the problem's ``:goal`` as a ``Multigoal`` (``on`` or ``served``),
from a copy of the bundled state (the copy is not timed) -- but through plain
``gtpyhop.find_plan`` (the session wrapper only adds overhead).  The
translations are not the HDDL: GTPyhop achieves the ``:goal`` only (ours:
the task network, then the goal), and its ``m2_do_on_table`` looks for the
block on top of ``?x``, where the HDDL unstacks ``?x`` from the block below.

Measured per instance: CPU time (``time.process_time``: the machines here are
shared), median of ``--runs`` runs (3 when one run takes over 2 s), ours and
GTPyhop interleaved; plan lengths; solved within ``--limit`` seconds.  The
JSON line has ``median_ratio`` (GTPyhop time over ours, on the instances both
solve), ``ours_solved``, ``gtpyhop_solved`` and more.

    python benchmarks/planner_vs_gtpyhop.py [--json] [--runs 5] [--limit 60] [--upto 30]
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import importlib.util
import io
import json
import os
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import _first  # noqa: F401  (this folder after the packages: see _first.py)

from planner import load_hddl, plan, validate

SUITE = Path(os.environ.get("SHARY_SUITES")
             or Path(__file__).resolve().parents[1].parent / "shared" / "suites") / "ipc2020"
"""The suite, where the README's "External suites" puts it (``$SHARY_SUITES`` moves it)."""
DOMAINS = {"Blocksworld-GTOHP": ("on", 30), "Childsnack": ("served", 30)}
"""Each domain: the attribute of GTPyhop's goal Multigoal, and how many instances."""
SLOW_S = 2.0
"""Beyond this CPU time for one run, an instance is run 3 times rather than --runs."""


def gtpyhop_bundle() -> tuple[Any, dict[str, Any]]:
    """GTPyhop and its bundled IPC 2020 domain packages (their folder names have
    hyphens, so they are loaded from their files)."""
    with contextlib.redirect_stdout(io.StringIO()):  # the packages print as they load
        import gtpyhop

        gtpyhop.set_verbose_level(0)
        base = Path(gtpyhop.__file__).parent / "examples" / "ipc-2020-total-order"
        packages = {}
        for name in DOMAINS:
            init = base / name / "__init__.py"
            if not init.is_file():
                raise SystemExit(f"GTPyhop's bundled {name} is not at {init.parent}: install "
                                 "the bench extra (pip install -e '.[bench]')")
            spec = importlib.util.spec_from_file_location(
                "gtpyhop_ipc_" + name.replace("-", "_"), init,
                submodule_search_locations=[str(init.parent)])
            assert spec is not None and spec.loader is not None
            module = importlib.util.module_from_spec(spec)
            sys.modules[spec.name] = module
            spec.loader.exec_module(module)
            packages[name] = module
    return gtpyhop, packages


def gtpyhop_instances(name: str, package: Any) -> dict[int, tuple[Any, Any]]:
    """GTPyhop's problems by instance number: (state, goal)."""
    out = {}
    for key, (state, goal, _) in package.get_problems().items():
        if name == "Childsnack":
            number = int(key.rsplit("_p", 1)[1])
        else:  # BW_rand_<blocks>: p01 is 5 blocks, p02 7, ... two more each
            number = (int(key.rsplit("_", 1)[1]) - 3) // 2
        out[number] = (state, goal)
    return out


def measure(run: Callable[[], tuple[Any, float]], runs: int, limit: float
            ) -> tuple[float, Any]:
    """The median CPU seconds of ``run`` (which times itself, leaving its set-up out)
    and its last result; 3 runs at most when one takes over :data:`SLOW_S`, one when
    it goes over the limit."""
    times: list[float] = []
    result = None
    while len(times) < runs:
        gc.collect()
        result, spent = run()
        times.append(spent)
        if spent > limit:
            break
        if spent > SLOW_S:
            runs = min(runs, 3)
    return statistics.median(times), result


def gtpyhop_solve(gtpyhop: Any, domain: Any, attribute: str, state: Any, goal: Any
                  ) -> tuple[Any, float]:
    """GTPyhop's plan for ``goal`` (a dict for the Multigoal's ``attribute``) from a
    copy of ``state``, and the CPU seconds of ``find_plan`` alone."""
    multigoal = gtpyhop.Multigoal("goal")
    setattr(multigoal, attribute, goal)
    fresh = state.copy()
    gtpyhop.set_current_domain(domain)
    try:
        return timed(lambda: gtpyhop.find_plan(fresh, [multigoal]))
    except RecursionError:
        return None, 0.0


def timed(call: Callable[[], Any]) -> tuple[Any, float]:
    start = time.process_time()
    result = call()
    return result, time.process_time() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true",
                        help="print one JSON line of figures (the table goes to stderr)")
    parser.add_argument("--runs", type=int, default=5, help="runs per instance (median)")
    parser.add_argument("--limit", type=float, default=60.0, metavar="S",
                        help="time limit per run, in CPU seconds")
    parser.add_argument("--suite", type=Path, default=SUITE, help="the ipc2020 folder")
    parser.add_argument("--upto", type=int, default=30, metavar="N",
                        help="only instances p01 to pN of each domain")
    args = parser.parse_args()
    total = args.suite / "total-order"
    if not total.is_dir():
        print(f"the IPC 2020 suite is not at {args.suite}: git clone --depth 1 "
              f"https://github.com/panda-planner-dev/ipc2020-domains {args.suite} (the "
              f"README's 'External suites'), or give --suite", file=sys.stderr)
        return 2
    gtpyhop, packages = gtpyhop_bundle()
    rows = []
    table = sys.stderr if args.json else sys.stdout  # with --json, stdout is one JSON line
    print(f"{'instance':<24} {'ours ms':>10} {'len':>5} {'GTPyhop ms':>11} {'len':>5} "
          f"{'ratio':>7}", file=table)
    for name, (attribute, count) in DOMAINS.items():
        theirs = gtpyhop_instances(name, packages[name])
        for number in range(1, min(count, args.upto) + 1):
            problem = load_hddl(total / name / "domain.hddl", total / name / f"p{number:02d}.hddl")
            ours_s, result = measure(
                lambda p=problem: timed(lambda: plan(p, args.limit * 1000, first=True)),
                args.runs, args.limit)
            ours_ok = (result.plan is not None and ours_s <= args.limit
                       and validate(problem, result.plan) == [])
            row = {"domain": name, "instance": f"p{number:02d}", "ours_ms": ours_s * 1000,
                   "ours_solved": ours_ok,
                   "ours_length": len(result.plan.actions) if result.plan else None,
                   "gtpyhop_ms": None, "gtpyhop_solved": None, "gtpyhop_length": None}
            if number in theirs:
                state, goal = theirs[number]

                domain = packages[name].the_domain

                def solve(state: Any = state, goal: Any = goal, domain: Any = domain,
                          attribute: str = attribute) -> tuple[Any, float]:
                    return gtpyhop_solve(gtpyhop, domain, attribute, state, goal)

                with contextlib.redirect_stdout(io.StringIO()):
                    their_s, found = measure(solve, args.runs, args.limit)
                row["gtpyhop_ms"] = their_s * 1000
                row["gtpyhop_solved"] = bool(found) and their_s <= args.limit
                row["gtpyhop_length"] = len(found) if found else None
            rows.append(row)
            ratio = (row["gtpyhop_ms"] / row["ours_ms"]
                     if row["ours_solved"] and row["gtpyhop_solved"] else None)
            row["ratio"] = ratio
            theirs_ms = row["gtpyhop_ms"] if row["gtpyhop_solved"] else None
            print(f"{name[:12] + ' ' + row['instance']:<24} "
                  f"{_show(row['ours_ms'] if ours_ok else None):>10} "
                  f"{_show(row['ours_length']):>5} "
                  f"{_show(theirs_ms, number in theirs):>11} "
                  f"{_show(row['gtpyhop_length'], number in theirs):>5} "
                  f"{_show(ratio, ratio is not None):>7}", file=table, flush=True)
    both = [r for r in rows if r["ratio"] is not None]
    figures = {
        "instances": len(rows),
        "ours_solved": sum(r["ours_solved"] for r in rows),
        "gtpyhop_instances": sum(r["gtpyhop_solved"] is not None for r in rows),
        "gtpyhop_solved": sum(bool(r["gtpyhop_solved"]) for r in rows),
        "both_solved": len(both),
        "median_ratio": round(statistics.median(r["ratio"] for r in both), 2) if both else None,
        "min_ratio": round(min(r["ratio"] for r in both), 2) if both else None,
        "only_ours": [f"{r['domain']} {r['instance']}" for r in rows
                      if r["ours_solved"] and not r["gtpyhop_solved"]],
        "runs": args.runs,
        "limit_s": args.limit,
        "gtpyhop_version": _version("gtpyhop"),
    }
    for name in DOMAINS:
        ratios = [r["ratio"] for r in both if r["domain"] == name]
        figures[f"median_ratio_{name.split('-')[0].lower()}"] = (
            round(statistics.median(ratios), 2) if ratios else None)
        solved = [r for r in rows if r["domain"] == name and r["ours_solved"]]
        figures[f"ours_ms_{name.split('-')[0].lower()}_largest"] = (
            round(solved[-1]["ours_ms"], 1) if solved else None)
    print(f"\nsolved: ours {figures['ours_solved']}/{figures['instances']}, GTPyhop "
          f"{figures['gtpyhop_solved']}/{figures['gtpyhop_instances']} (its translations); "
          f"median ratio GTPyhop/ours on the {len(both)} both solve: {figures['median_ratio']}",
          file=table)
    print(f"solved by ours only: {', '.join(figures['only_ours']) or 'none'}", file=table)
    if args.json:
        print(json.dumps(figures))
    return 0


def _show(value: float | None, exists: bool = True) -> str:
    if not exists:
        return "-"
    if value is None:
        return "FAIL"
    return f"{value:.2f}" if isinstance(value, float) else str(value)


def _version(package: str) -> str | None:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(package)
    except PackageNotFoundError:
        return None


if __name__ == "__main__":
    sys.exit(main())
